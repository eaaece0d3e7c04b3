"""Options shared by the sub-commands (`--connect`, `--space`, `--timeout`, `--secure`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from space.zconfig import DEFAULT_ENDPOINT, SECURE_ENDPOINT

if TYPE_CHECKING:
    import zenoh

    from space.client import TripleSpace
    from space.identity import Identity


def add_connect(parser: argparse.ArgumentParser, *, space: str | None = "default") -> None:
    """Add `--connect`, `--config`, `--space` and `--timeout` to a client sub-command.

    `space` is `--space`'s default; None: the one the store holds (see `open_space`).
    """
    parser.add_argument(
        "--connect",
        metavar="ENDPOINT",
        action="append",
        help=f"Zenoh endpoint of a router (repeatable; default {DEFAULT_ENDPOINT}, "
        f"{SECURE_ENDPOINT} with --secure)",
    )
    parser.add_argument("--config", metavar="FILE", help="a Zenoh JSON5 configuration file")
    add_secure(parser, "operator, or the agent's name")
    parser.add_argument(
        "--space",
        default=space,
        help=f"name of the space (default: {space})"
        if space
        else "name of the space (default: the one the store holds, e.g. the one `tspace up` "
        "runs; 'default' if it holds none)",
    )
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


def open_space(args: argparse.Namespace, agent: str, *, create: bool = False) -> TripleSpace:
    """Open the space named by `--space` through the routers of `--connect`.

    The store says which spaces it holds: with no `--space`, the one it holds
    (the one `tspace up` runs) is used, 'default' if it holds none; a space it
    does not hold is an error naming those it does, unless `create` (a write
    makes a new space, and one naming its space asks nothing first).

    With `--secure`, as `--identity` (default: the operator); a secure store answers
    only its own keys, so there `--space` is taken as given ('default' if none).

    Raises:
        InputError: `--space` is not a legal space name, or not one the store holds.
        UsageError: no `--space`, and the store holds several.
        ConfigError: a `--connect` endpoint or the `--config` file is malformed, or
            the `--secure` directory lacks the identity's certificate.
        SpaceUnavailable, SpaceTimeout: no router, or no store answered.
    """
    from space._session import open_session
    from space.client import TripleSpace
    from space.keys import check_space

    if args.space is not None:
        check_space(args.space)
    identity = identity_of(args, "operator")
    if identity is not None:
        return TripleSpace.open(
            args.connect,
            space=args.space or "default",
            agent=agent,
            config_file=args.config,
            identity=identity,
        )
    session = open_session(args.connect, config_file=args.config)
    try:
        if args.space is not None and create:
            name = args.space  # a write may name any space: nothing to ask the store
        else:
            name = pick_space(args.space, store_spaces(session, args.timeout), create=create)
        return TripleSpace(session, name, agent=agent, _owns_session=True)
    except BaseException:
        session.close()
        raise


def store_spaces(session: zenoh.Session, timeout: float) -> dict[str, int]:
    """Return the spaces the store holds, with their sequence numbers.

    Raises:
        SpaceUnavailable, SpaceTimeout: no store answered.
    """
    from space._request import ask_store
    from space.changeset import pack
    from space.keys import ROOT

    reply = ask_store(session, f"{ROOT}/@repl/spaces", pack({}), timeout, what="spaces request")
    return {str(k): int(v) for k, v in reply.items() if isinstance(v, int)}


def pick_space(requested: str | None, spaces: dict[str, int], *, create: bool) -> str:
    """Return the space to use, given `--space` and the spaces the store holds.

    Raises:
        InputError: `requested` is not held (and not `create`).
        UsageError: nothing requested, and the store holds several spaces.
    """
    from space.errors import InputError, UsageError

    known = sorted(name for name, seq in spaces.items() if seq > 0)
    if requested is None:
        if len(known) == 1:
            return known[0]
        if not known or "default" in known:
            return "default"
        raise UsageError(f"the store holds several spaces ({', '.join(known)}): give --space")
    if requested in known or create:
        return requested
    raise InputError(
        f"no space {requested!r} in the store; it holds: {', '.join(known) or 'none yet'}"
    )
