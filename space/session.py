"""Open Zenoh sessions with errors a user can act on."""

from __future__ import annotations

import zenoh

from space.errors import SpaceUnavailable
from space.zconfig import make_config


def open_session(
    connect: list[str] | None = None, *, mode: str = "client", config_file: str | None = None
) -> zenoh.Session:
    """Open a Zenoh session connected to the given routers.

    Raises:
        SpaceUnavailable: no router could be reached.
    """
    conf = make_config(mode=mode, connect=connect, config_file=config_file)
    try:
        return zenoh.open(conf)
    except zenoh.ZError as exc:
        where = ", ".join(connect) if connect else "the configured endpoints"
        raise SpaceUnavailable(f"no Zenoh router reachable at {where}") from exc
