"""Who a process is in a secure space: its certificate, key and the fleet's CA.

Every process of a secure fleet speaks mutual TLS with a certificate signed
by the fleet's CA; the certificate's common name (CN) is its identity, the
name the routers' access control and the store's policy know it by. A
certificate directory (made by `tspace certs init`) holds `ca.pem`, and
`NAME.pem` and `NAME.key` for each identity.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from space.errors import ConfigError, InputError

# A CN is a Zenoh key chunk too (the write key names the writer), and a file name.
_NAME_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]*$")


@dataclass(frozen=True)
class Identity:
    """The files one process needs to speak mTLS as `name`."""

    directory: Path
    name: str

    @property
    def ca(self) -> Path:
        """The fleet CA's certificate, which every peer's certificate must be signed by."""
        return self.directory / "ca.pem"

    @property
    def cert(self) -> Path:
        """This identity's certificate (CN = `name`)."""
        return self.directory / f"{self.name}.pem"

    @property
    def key(self) -> Path:
        """This identity's private key (mode 0600)."""
        return self.directory / f"{self.name}.key"


def check_name(name: str) -> str:
    """Return `name` if it can be an identity (a CN, a key chunk, a file name).

    Raises:
        InputError: it cannot.
    """
    if not _NAME_RE.match(name):
        raise InputError(f"identity {name!r}: use letters, digits, '_', '-' or '.'")
    return name


def load_identity(directory: str | Path, name: str) -> Identity:
    """Return the identity `name` of a certificate directory, checked to be complete.

    Raises:
        ConfigError: the CA's certificate, or the identity's certificate or key, is missing.
    """
    identity = Identity(Path(directory), check_name(name))
    missing = [p.name for p in (identity.ca, identity.cert, identity.key) if not p.is_file()]
    if missing:
        raise ConfigError(
            f"no identity {name!r} in {directory}: missing {', '.join(missing)} "
            f"(tspace certs init / tspace certs issue)"
        )
    return identity
