"""Options shared by the sub-commands (`--connect`, `--space`, `--timeout`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from space.zconfig import DEFAULT_ENDPOINT

if TYPE_CHECKING:
    from space.client import TripleSpace


def add_connect(parser: argparse.ArgumentParser) -> None:
    """Add `--connect`, `--config` and `--space` to a client sub-command."""
    parser.add_argument(
        "--connect",
        metavar="ENDPOINT",
        action="append",
        help=f"Zenoh endpoint of a router (repeatable; default {DEFAULT_ENDPOINT})",
    )
    parser.add_argument("--config", metavar="FILE", help="a Zenoh JSON5 configuration file")
    parser.add_argument("--space", default="default", help="name of the space (default: default)")
    parser.add_argument(
        "--timeout",
        type=float,
        default=5.0,
        metavar="SECONDS",
        help="how long to wait for the store (default 5)",
    )


def open_space(args: argparse.Namespace, agent: str) -> TripleSpace:
    """Open the space named by `--space` through the routers of `--connect`.

    Raises:
        InputError: `--space` is not a legal space name.
        ConfigError: a `--connect` endpoint or the `--config` file is malformed.
        SpaceUnavailable: no router reachable.
    """
    from space.client import TripleSpace

    return TripleSpace.open(args.connect, space=args.space, agent=agent, config_file=args.config)
