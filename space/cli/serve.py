"""`tspace serve`: run the embedded Zenoh router and the space store."""

from __future__ import annotations

import argparse
from pathlib import Path

from space.cli.options import add_secure, identity_of
from space.zconfig import DEFAULT_ENDPOINT

ORDER = 20


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `serve` sub-command."""
    p = sub.add_parser(
        "serve",
        help="run a Zenoh router with the space store (the embedded default)",
        description="Run a Zenoh router and the persistent store of every space, until Ctrl-C.",
    )
    p.add_argument(
        "--listen",
        metavar="ENDPOINT",
        action="append",
        help=f"endpoint to listen on (repeatable; default {DEFAULT_ENDPOINT})",
    )
    p.add_argument(
        "--connect", metavar="ENDPOINT", action="append", help="other routers to mesh with"
    )
    p.add_argument("--config", metavar="FILE", help="a Zenoh JSON5 configuration file")
    add_secure(p, "store, or router with --no-store")
    p.add_argument(
        "--policy",
        metavar="FILE",
        help="with --secure: who may do what (default deploy/policy.toml, here)",
    )
    p.add_argument(
        "--data", metavar="DIR", type=Path, help="where the store persists (default: user data dir)"
    )
    p.add_argument(
        "--fsync",
        action="store_true",
        help="flush every commit to disk before acknowledging it (survives power loss, "
        "slower; without it a commit survives kill -9 of the store, not of the machine)",
    )
    p.add_argument(
        "--log-keep",
        metavar="N",
        type=int,
        default=100_000,
        help="changesets of each space kept for late subscribers and returning stores "
        "(default 100000; one away longer is copied whole)",
    )
    p.add_argument(
        "--query-timeout",
        metavar="SECONDS",
        type=float,
        default=10.0,
        help="time limit of a read (SPARQL, template, log); a request may ask for less "
        "(default 10)",
    )
    p.add_argument(
        "--max-spaces",
        metavar="N",
        type=int,
        default=10_000,
        help="spaces this store holds at most; a write to one more is refused (default 10000)",
    )
    p.add_argument(
        "--cluster",
        metavar="HOST:PORT,...",
        type=etcd_members,
        help="be one replica of a store replicated on this etcd cluster (its members' client "
        "addresses, comma-separated; docs/cluster.md); default: one store, no etcd",
    )
    p.add_argument(
        "--no-store", action="store_true", help="route only: another process keeps the space"
    )
    p.set_defaults(func=run)


def etcd_members(text: str) -> list[str]:
    """Parse `--cluster`: etcd members' `host:port`, comma-separated."""
    members = [m.strip() for m in text.split(",") if m.strip()]
    for m in members:
        host, _, port = m.rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise argparse.ArgumentTypeError(f"{m!r} is not HOST:PORT (an etcd client address)")
    if not members:
        raise argparse.ArgumentTypeError("no etcd member given (HOST:PORT,HOST:PORT,...)")
    return members


def run(args: argparse.Namespace) -> int:
    """Serve until interrupted."""
    import logging

    from space.errors import UsageError
    from space.serve import serve_forever

    if args.policy and not args.secure:
        raise UsageError("--policy needs --secure DIR")
    if args.cluster and args.no_store:
        raise UsageError("--cluster runs a store replica: it cannot go with --no-store")
    logging.getLogger("tspace").setLevel(min(logging.getLogger().level, logging.INFO))
    serve_forever(
        listen=args.listen,
        data_dir=args.data,
        durable=args.fsync,
        log_keep=args.log_keep,
        query_timeout=args.query_timeout,
        max_spaces=args.max_spaces,
        config_file=args.config,
        connect=args.connect,
        store=not args.no_store,
        identity=identity_of(args, "router" if args.no_store else "store"),
        policy_file=args.policy,
        cluster=args.cluster,
    )
    return 0
