"""Turn command-line style options into a `zenoh.Config`.

Every agent and CLI command goes through here so that `--connect`, `--listen`
and `--config` mean the same thing everywhere, and fail the same way: a
malformed endpoint or configuration file is a `ConfigError`, one line.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import TYPE_CHECKING

import zenoh

from space.errors import ConfigError

if TYPE_CHECKING:
    from space.identity import Identity

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
SECURE_ENDPOINT = "tls/127.0.0.1:7447"

# Zenoh appends the Rust source location to its messages: noise for a user.
_RUST_LOCATION_RE = re.compile(r"\s+at /\S+\.rs:\d+\.?")
_JSON5_MSG_RE = re.compile(r'msg: "((?:[^"\\]|\\.)*)"')


def make_config(
    *,
    mode: str = "client",
    connect: list[str] | None = None,
    listen: list[str] | None = None,
    config_file: str | Path | None = None,
    identity: Identity | None = None,
    access_control: dict | None = None,
) -> zenoh.Config:
    """Build a Zenoh configuration.

    Args:
        mode: "client", "peer" or "router".
        connect: endpoints to connect to (default: the embedded router's endpoint
            for clients and peers, none for routers).
        listen: endpoints to listen on (routers default to `DEFAULT_ENDPOINT`).
        config_file: a Zenoh JSON5 configuration file read first; the options
            above override what it says.
        identity: speak mutual TLS as this identity, and nothing else: every
            endpoint must be `tls/` (the default ones are) and plain links are refused.
        access_control: Zenoh `access_control` settings this node enforces (a router's).

    Raises:
        ConfigError: the file cannot be read or parsed, or an endpoint is malformed
            or, with `identity`, not TLS.
    """
    conf = _read_file(config_file) if config_file else zenoh.Config()
    _insert(conf, "mode", mode)
    default = DEFAULT_ENDPOINT if identity is None else SECURE_ENDPOINT
    if connect is None and mode != "router" and not config_file:
        connect = [default]
    if listen is None and mode == "router" and not config_file:
        listen = [default]
    if access_control is not None:
        _insert(conf, "access_control", access_control)
    if connect is not None:
        _insert_endpoints(conf, "connect/endpoints", connect)
    if listen is not None:
        _insert_endpoints(conf, "listen/endpoints", listen)
    if identity is not None:
        _secure(conf, identity, mode)
    if not config_file:
        # Explicit endpoints only: multicast scouting would make separate test
        # routers on one machine find each other and merge their spaces.
        conf.insert_json5("scouting/multicast/enabled", "false")
    return conf


def _secure(conf: zenoh.Config, identity: Identity, mode: str) -> None:
    """Make every link mutual TLS with `identity`'s certificate; refuse any other link.

    Every endpoint, given as an option or in a configuration file, must be TLS.
    """
    endpoints = _endpoints(conf, "connect/endpoints", mode)
    if mode != "client":
        endpoints += _endpoints(conf, "listen/endpoints", mode)
    plain = [e for e in endpoints if not e.startswith("tls/")]
    if plain:
        raise ConfigError(f"secure mode speaks TLS only: use tls/HOST:PORT, not {plain[0]!r}")
    files = {
        "root_ca_certificate": identity.ca,
        "listen_private_key": identity.key,
        "listen_certificate": identity.cert,
        "connect_private_key": identity.key,
        "connect_certificate": identity.cert,
    }
    tls = {name: str(path.resolve()) for name, path in files.items()}
    tls["enable_mtls"] = True  # type: ignore[assignment]
    _insert(conf, "transport/link/tls", tls)
    _insert(conf, "transport/link/protocols", ["tls"])


def _endpoints(conf: zenoh.Config, key: str, mode: str) -> list[str]:
    """Return the endpoints set at `key` (a list, or one list per mode)."""
    value = json.loads(conf.get_json(key))
    if isinstance(value, dict):
        value = value.get(mode, [])
    return [str(e) for e in value]


def zenoh_reason(exc: zenoh.ZError) -> str:
    """Return the part of a Zenoh error a user can act on, on one line."""
    text = _RUST_LOCATION_RE.sub("", str(exc))
    if (found := _JSON5_MSG_RE.search(text)) is not None:
        text = found.group(1)
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    # A JSON5 syntax error spans lines: `--> line:col`, the source, `= what was expected`.
    where = next((line[3:].strip() for line in lines if line.startswith("-->")), None)
    what = next((line[1:].strip() for line in lines if line.startswith("=")), None)
    if what is not None:
        return f"line {where}: {what}" if where else what
    return " ".join(lines)


def _read_file(path: str | Path) -> zenoh.Config:
    try:
        return zenoh.Config.from_file(str(path))
    except zenoh.ZError as exc:
        raise ConfigError(f"cannot read Zenoh configuration {path}: {zenoh_reason(exc)}") from exc


def _insert(conf: zenoh.Config, key: str, value: object) -> None:
    try:
        conf.insert_json5(key, json.dumps(value))
    except zenoh.ZError as exc:
        raise ConfigError(f"bad {key} {value!r}: {zenoh_reason(exc)}") from exc


def _insert_endpoints(conf: zenoh.Config, key: str, endpoints: list[str]) -> None:
    """Insert endpoints, naming the first malformed one if Zenoh refuses them."""
    for endpoint in endpoints:
        try:
            zenoh.Config().insert_json5(key, json.dumps([endpoint]))
        except zenoh.ZError as exc:
            reason = zenoh_reason(exc).removesuffix(f": {endpoint}")
            raise ConfigError(f"bad endpoint {endpoint!r}: {reason}") from exc
    _insert(conf, key, endpoints)
