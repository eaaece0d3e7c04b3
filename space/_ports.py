"""Try a port before a server takes it, so that a launcher says at once that it is taken."""

from __future__ import annotations

import socket


def probe(host: str, port: int, kind: int = socket.SOCK_STREAM) -> None:
    """Bind `host:port` and release it at once, as a server would bind it.

    With SO_REUSEADDR, as Zenoh's listeners and `http.server` set it: a port in
    TIME_WAIT is free, a listening one is not.

    Raises:
        OSError: the port is taken, or `host` is not an address of this machine.
    """
    family, _, _, _, where = socket.getaddrinfo(host.strip("[]"), port, type=kind)[0]
    with socket.socket(family, kind) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind(where)


def any_free_port(host: str) -> int:
    """Return a TCP port free on `host` now, chosen by the kernel."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])
