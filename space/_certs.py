"""A fleet's certificate authority and the certificates of its identities.

Every process of a secure fleet speaks mutual TLS: it shows a certificate
signed by the fleet's CA, and its common name (CN) is its identity, the name
Zenoh's access control and the store's policy know it by. A directory holds
`ca.pem` (the CA's certificate, public), `ca.key` (the CA's key: keep it off
the robots) and `NAME.pem` / `NAME.key` for each identity. Keys are written
0600. Everything is made with the `cryptography` package.
"""

from __future__ import annotations

import datetime as dt
import ipaddress
import os
import tomllib
from collections.abc import Iterable
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from space.errors import InputError
from space.identity import Identity, check_name

SERVERS = ("router", "store")
OPERATOR = "operator"
DEFAULT_HOSTS = ("localhost", "127.0.0.1")
_VALID_DAYS = 825


def hosts_for(name: str, extra: Iterable[str] = ()) -> list[str]:
    """Return the addresses a certificate for `name` must name (a router is dialled at them).

    Servers: loopback and `extra` (the addresses other hosts dial); a robot host's
    router (`router.ROBOT`): loopback, where its own agents dial it; others: none.
    """
    if name in SERVERS:
        return [*DEFAULT_HOSTS, *extra]
    return list(DEFAULT_HOSTS) if name.startswith("router.") else []


def fleet_identities(launch_file: str | Path) -> list[str]:
    """Return the identities a launch file's processes run as.

    A per-robot agent runs as `KIND.ROBOT` (the agent's own name), a fleet
    agent as `KIND`; the store, the router, each robot host's router
    (`router.ROBOT`) and the operator are added.

    Raises:
        InputError: the file cannot be read or is not a launch file.
    """
    try:
        data = tomllib.loads(Path(launch_file).read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise InputError(f"{launch_file}: {exc}") from exc
    robots = data.get("robots", ["robot1"])
    agents = data.get("agent", [])
    if not isinstance(robots, list) or not isinstance(agents, list):
        raise InputError(f"{launch_file}: robots and [[agent]] must be lists")
    names = [*SERVERS, OPERATOR, *(f"router.{robot}" for robot in robots)]
    for entry in agents:
        if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
            raise InputError(f"{launch_file}: every [[agent]] needs a name")
        if entry.get("per_robot", False):
            names += [f"{entry['name']}.{robot}" for robot in robots]
        else:
            names.append(entry["name"])
    return [check_name(n) for n in dict.fromkeys(names)]


def init_authority(directory: Path) -> None:
    """Make the fleet's CA in `directory` (created), unless one is there.

    Raises:
        InputError: `directory` holds half a CA (a certificate without its key or back).
    """
    directory.mkdir(parents=True, exist_ok=True)
    cert, key = directory / "ca.pem", directory / "ca.key"
    if cert.exists() and key.exists():
        return
    if cert.exists() or key.exists():
        raise InputError(f"{directory} holds one of ca.pem and ca.key only: restore or remove it")
    private = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "tspace fleet CA")])
    now = dt.datetime.now(dt.UTC)
    ca = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(private.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(minutes=5))
        .not_valid_after(now + dt.timedelta(days=3650))
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=True,
                key_cert_sign=True,
                crl_sign=True,
                content_commitment=False,
                key_encipherment=False,
                data_encipherment=False,
                key_agreement=False,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(private.public_key()), False)
        .sign(private, hashes.SHA256())
    )
    _write_key(key, private)
    cert.write_bytes(ca.public_bytes(serialization.Encoding.PEM))


def issue(directory: Path, name: str, hosts: Iterable[str] = ()) -> Identity:
    """Sign a new key and certificate for `name` with the CA in `directory`; replace old ones.

    `hosts` (DNS names or IP addresses) go into the certificate's subject
    alternative names: a router's certificate must name every address it is
    dialled at, since TLS clients check it; a client's needs none.

    Raises:
        InputError: `name` is not a legal identity, or there is no CA in `directory`.
    """
    check_name(name)
    try:
        ca_key = serialization.load_pem_private_key((directory / "ca.key").read_bytes(), None)
        ca_cert = x509.load_pem_x509_certificate((directory / "ca.pem").read_bytes())
    except (OSError, ValueError) as exc:
        raise InputError(f"no usable CA in {directory} (tspace certs init): {exc}") from exc
    assert isinstance(ca_key, ec.EllipticCurvePrivateKey)
    private = ec.generate_private_key(ec.SECP256R1())
    now = dt.datetime.now(dt.UTC)
    builder = (
        x509.CertificateBuilder()
        .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, name)]))
        .issuer_name(ca_cert.subject)
        .public_key(private.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(minutes=5))
        .not_valid_after(now + dt.timedelta(days=_VALID_DAYS))
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(
            x509.ExtendedKeyUsage(
                [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
            ),
            critical=False,
        )
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()), False
        )
    )
    names = [_san(h) for h in hosts]
    if names:
        builder = builder.add_extension(x509.SubjectAlternativeName(names), critical=False)
    cert = builder.sign(ca_key, hashes.SHA256())
    identity = Identity(directory, name)
    _write_key(identity.key, private)
    identity.cert.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    return identity


def common_name(cert_file: Path) -> str:
    """Return the CN of a PEM certificate ('' if it has none)."""
    cert = x509.load_pem_x509_certificate(cert_file.read_bytes())
    names = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    return str(names[0].value) if names else ""


def _san(host: str) -> x509.GeneralName:
    try:
        return x509.IPAddress(ipaddress.ip_address(host))
    except ValueError:
        return x509.DNSName(host)


def _write_key(path: Path, key: ec.EllipticCurvePrivateKey) -> None:
    """Write a private key readable by its owner only, from the first byte on."""
    data = key.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )
    path.unlink(missing_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as out:
        out.write(data)
