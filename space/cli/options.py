"""Options shared by the sub-commands (`--connect`, `--space`, `--timeout`, `--secure`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from space.zconfig import DEFAULT_ENDPOINT, SECURE_ENDPOINT

if TYPE_CHECKING:
    from space.client import TripleSpace
    from space.identity import Identity


def add_connect(parser: argparse.ArgumentParser) -> None:
    """Add `--connect`, `--config` and `--space` to a client sub-command."""
    parser.add_argument(
        "--connect",
        metavar="ENDPOINT",
        action="append",
        help=f"Zenoh endpoint of a router (repeatable; default {DEFAULT_ENDPOINT}, "
        f"{SECURE_ENDPOINT} with --secure)",
    )
    parser.add_argument("--config", metavar="FILE", help="a Zenoh JSON5 configuration file")
    add_secure(parser, "operator, or the agent's name")
    parser.add_argument("--space", default="default", help="name of the space (default: default)")
    parser.add_argument(
        "--timeout",
        type=float,
        default=5.0,
        metavar="SECONDS",
        help="how long to wait for the store (default 5)",
    )


def add_secure(parser: argparse.ArgumentParser, default: str) -> None:
    """Add `--secure DIR` and `--identity NAME` (whose certificate; `default` says the default)."""
    parser.add_argument(
        "--secure",
        metavar="DIR",
        help="speak mutual TLS only, with the certificates of DIR (tspace certs init)",
    )
    parser.add_argument(
        "--identity",
        metavar="NAME",
        help=f"with --secure: whose certificate to use (default {default})",
    )


def identity_of(args: argparse.Namespace, default: str) -> Identity | None:
    """Return the identity `--secure`/`--identity` name, or None without `--secure`.

    Raises:
        UsageError: `--identity` without `--secure`.
        ConfigError: the directory lacks the CA's or the identity's certificate or key.
    """
    from space.errors import UsageError
    from space.identity import load_identity

    if args.secure is None:
        if args.identity is not None:
            raise UsageError("--identity needs --secure DIR")
        return None
    return load_identity(args.secure, args.identity or default)


def open_space(args: argparse.Namespace, agent: str) -> TripleSpace:
    """Open the space named by `--space` through the routers of `--connect`.

    With `--secure`, as `--identity` (default: the operator).

    Raises:
        InputError: `--space` is not a legal space name.
        ConfigError: a `--connect` endpoint or the `--config` file is malformed, or
            the `--secure` directory lacks the identity's certificate.
        SpaceUnavailable: no router reachable.
    """
    from space.client import TripleSpace

    return TripleSpace.open(
        args.connect,
        space=args.space,
        agent=agent,
        config_file=args.config,
        identity=identity_of(args, "operator"),
    )
