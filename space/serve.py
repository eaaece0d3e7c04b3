"""The embedded default: a Zenoh router and the space store in one process."""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import zenoh

from space._heap import freeze_startup
from space._session import open_router
from space._stopping import on_stop_signals
from space.errors import InputError
from space.identity import Identity
from space.store.guard import WriteGuard
from space.store.server import StoreServer

if TYPE_CHECKING:
    from space.store.cluster_server import ClusterStoreServer

log = logging.getLogger("tspace.serve")
DEFAULT_POLICY = Path("deploy/policy.toml")  # in the current directory


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
    identity: Identity | None = None,
    policy_file: str | Path | None = None,
    cluster: list[str] | None = None,
) -> Iterator[StoreServer | ClusterStoreServer | None]:
    """Open a router-mode Zenoh session with the store on it (unless `store=False`); close both.

    With `identity`, the router speaks mutual TLS only and enforces the policy
    (`policy_file`, default `DEFAULT_POLICY`) on its clients, and
    the store checks every write against it. With `cluster` (etcd members'
    `host:port`), the store is a replica of that cluster (docs/cluster.md).

    Raises:
        InputError: the policy file is missing, cannot be read or is malformed.
        ConfigError: an endpoint or the configuration file is malformed.
        ListenFailed: the router cannot listen (the port is taken, say).
    """
    from space._paths import default_data_dir

    guard, acl = _secure_parts(identity, policy_file)
    session = open_router(
        listen, connect=connect, config_file=config_file, identity=identity, access_control=acl
    )
    try:
        listener = session.info.declare_transport_events_listener(_log_transport)
        server: StoreServer | ClusterStoreServer
        if cluster:
            from space.store.cluster_server import ClusterStoreServer  # imports etcd's client

            server = ClusterStoreServer(
                session,
                data_dir or default_data_dir(),
                cluster,
                durable=durable,
                log_keep=log_keep,
                query_timeout=query_timeout,
                max_spaces=max_spaces,
                guard=guard,
            )
        else:
            server = StoreServer(
                session,
                data_dir or default_data_dir(),
                durable=durable,
                log_keep=log_keep,
                query_timeout=query_timeout,
                max_spaces=max_spaces,
                guard=guard,
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


def _secure_parts(
    identity: Identity | None, policy_file: str | Path | None
) -> tuple[WriteGuard | None, dict | None]:
    """Return the store's write guard and the router's access control, or None, None."""
    if identity is None:
        return None, None
    from space._acl import access_control
    from space._policy import read_policy

    if policy_file is None and not DEFAULT_POLICY.exists():
        raise InputError(f"secure mode needs a policy: --policy FILE (no {DEFAULT_POLICY} here)")
    policy = read_policy(policy_file or DEFAULT_POLICY)
    log.info("secure: mTLS as %s; %d identities in the policy", identity.name, len(policy.roles))
    return WriteGuard(policy), access_control(policy)


def _log_transport(event: zenoh.TransportEvent) -> None:
    t = event.transport
    verb = "connected" if event.kind == zenoh.SampleKind.PUT else "disconnected"
    log.info("%s %s %s", t.whatami, t.zid, verb)


def serve_forever(**kwargs: object) -> None:
    """Run `open_server(**kwargs)` until SIGINT or SIGTERM; raises what `open_server` raises."""
    stop = threading.Event()
    with on_stop_signals(stop.set), open_server(**kwargs) as server:  # type: ignore[arg-type]
        if server is None:
            log.info("routing only (no store)")
        else:
            log.info("serving spaces from %s", server.data_dir)
        freeze_startup()
        stop.wait()
        log.info("stopping")
