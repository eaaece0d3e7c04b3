"""Open Zenoh sessions with errors a user can act on."""

from __future__ import annotations

import re
import socket
from typing import TYPE_CHECKING

import zenoh

from space._ports import probe
from space.errors import ListenFailed, SpaceUnavailable, clause
from space.zconfig import make_config, zenoh_reason

if TYPE_CHECKING:
    from space.identity import Identity

# "Can not create a new TCP listener bound to tcp/127.0.0.1:7447: [127.0.0.1:7447:
# Address already in use (os error 98) ...": which endpoint, and the OS's reason.
_LISTENER_RE = re.compile(
    r"bound to (?P<endpoint>\S+): \[.*?: (?P<why>[^:\[\]]+?) \(os error \d+\)"
)


def open_session(
    connect: list[str] | None = None,
    *,
    mode: str = "client",
    config_file: str | None = None,
    identity: Identity | None = None,
) -> zenoh.Session:
    """Open a Zenoh session connected to the given routers (with mTLS as `identity` if given).

    Raises:
        ConfigError: an endpoint or the configuration file is malformed.
        SpaceUnavailable: no router could be reached (or, secure, none accepted the certificate).
    """
    conf = make_config(mode=mode, connect=connect, config_file=config_file, identity=identity)
    try:
        return zenoh.open(conf)
    except zenoh.ZError as exc:
        where = ", ".join(connect) if connect else "the configured endpoints"
        raise SpaceUnavailable(f"no Zenoh router reachable at {where}") from exc


def open_router(
    listen: list[str] | None = None,
    *,
    connect: list[str] | None = None,
    config_file: str | None = None,
    identity: Identity | None = None,
    access_control: dict | None = None,
) -> zenoh.Session:
    """Open a router-mode session listening on `listen` (default: `DEFAULT_ENDPOINT`).

    With `identity`, every link is mutual TLS (default endpoint `SECURE_ENDPOINT`)
    and the router enforces `access_control` on its clients.

    Raises:
        ConfigError: an endpoint or the configuration file is malformed.
        ListenFailed: a listener could not be opened (the port is taken, say).
    """
    conf = make_config(
        mode="router",
        listen=listen,
        connect=connect,
        config_file=config_file,
        identity=identity,
        access_control=access_control,
    )
    try:
        return zenoh.open(conf)
    except zenoh.ZError as exc:
        raise listen_failed(exc, listen) from exc


def listen_failed(exc: zenoh.ZError, listen: list[str] | None) -> ListenFailed:
    """Return the one-line error for a router that could not open its listeners."""
    reason = zenoh_reason(exc)
    found = _LISTENER_RE.search(reason)
    if found is not None:
        return ListenFailed(f"cannot listen on {found.group('endpoint')}: {clause(found['why'])}")
    where = ", ".join(listen) if listen else "the configured endpoints"
    return ListenFailed(f"cannot listen on {where}: {reason}")


def check_can_listen(listen: list[str]) -> None:
    """Fail now if a router could not listen on these endpoints (a launcher's early check).

    Only TCP, TLS and UDP endpoints are tried (bound and released at once); the
    router itself has the last word on the others.

    Raises:
        ConfigError: an endpoint is malformed.
        ListenFailed: the address is taken or not one of this host.
    """
    make_config(mode="router", listen=listen)
    for endpoint in listen:
        protocol, _, address = endpoint.partition("/")
        kind = {"tcp": socket.SOCK_STREAM, "tls": socket.SOCK_STREAM, "udp": socket.SOCK_DGRAM}.get(
            protocol
        )
        host, _, port = re.split(r"[?#]", address, maxsplit=1)[0].rpartition(":")
        if kind is None or not port.isdigit():
            continue
        try:
            probe(host, int(port), kind)
        except OSError as exc:
            why = clause(exc.strerror or str(exc))
            raise ListenFailed(f"cannot listen on {endpoint}: {why}") from exc
