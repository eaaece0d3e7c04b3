"""The embedded default: a Zenoh router and the space store in one process."""

from __future__ import annotations

import logging
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import zenoh

from space.heap import freeze_startup
from space.session import open_router
from space.store.server import StoreServer

log = logging.getLogger("tspace.serve")


@contextmanager
def open_server(
    listen: list[str] | None = None,
    data_dir: Path | None = None,
    *,
    durable: bool = False,
    log_keep: int = 100_000,
    query_timeout: float = 10.0,
    max_spaces: int = 10_000,
    config_file: str | None = None,
    connect: list[str] | None = None,
    store: bool = True,
) -> Iterator[StoreServer | None]:
    """Open a router-mode Zenoh session with the store on it (unless `store=False`); close both.

    Raises:
        ConfigError: an endpoint or the configuration file is malformed.
        ListenFailed: the router cannot listen (the port is taken, say).
    """
    from space.paths import default_data_dir

    session = open_router(listen, connect=connect, config_file=config_file)
    try:
        listener = session.info.declare_transport_events_listener(_log_transport)
        # Meshed with other routers, a store first looks a while for a leading store there.
        server = StoreServer(
            session,
            data_dir or default_data_dir(),
            durable=durable,
            log_keep=log_keep,
            query_timeout=query_timeout,
            max_spaces=max_spaces,
            look_for_leader=2.0 if connect else 0.0,
        )
        if store:
            server.start()
        try:
            yield server if store else None
        finally:
            server.close()
            listener.undeclare()
    finally:
        session.close()


def _log_transport(event: zenoh.TransportEvent) -> None:
    t = event.transport
    verb = "connected" if event.kind == zenoh.SampleKind.PUT else "disconnected"
    log.info("%s %s %s", t.whatami, t.zid, verb)


def serve_forever(**kwargs: object) -> None:
    """Run `open_server(**kwargs)` until SIGINT or SIGTERM; raises what `open_server` raises."""
    stop = threading.Event()
    previous = {
        sig: signal.signal(sig, lambda *_: stop.set()) for sig in (signal.SIGINT, signal.SIGTERM)
    }
    try:
        with open_server(**kwargs) as server:  # type: ignore[arg-type]
            if server is None:
                log.info("routing only (no store)")
            else:
                log.info("serving spaces from %s", server.data_dir)
            freeze_startup()
            stop.wait()
            log.info("stopping")
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
