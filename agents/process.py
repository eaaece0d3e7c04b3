"""An agent as a process: its command line, its logging, its signals.

Apart from the lifecycle (`agents.base`): an agent is the same object whether
run as a process (`run_agent`, the `__main__` of every `agents/NAME.py`) or
built by a test from `build_parser`'s arguments; only a process configures
logging and turns SIGINT and SIGTERM into `stop()`. `agents.base` re-exports
both names, which every agent imports from there.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from space import (
    InputError,
    SpaceError,
    add_connect,
    check_lifespan,
    freeze_startup,
    on_stop_signals,
)

if TYPE_CHECKING:
    from agents.base import Agent


def build_parser(cls: type[Agent], prog: str | None = None) -> argparse.ArgumentParser:
    """Return the command-line parser of an agent class: common options, then its own.

    `prog` is how the agent was run, for its usage line (`python -m agents.KIND` by default).
    """
    parser = argparse.ArgumentParser(
        prog=prog or f"python -m agents.{cls.kind}", description=(cls.__doc__ or "").split("\n")[0]
    )
    add_connect(parser)
    parser.add_argument(
        "--robot", default="robot1", help="the robot served: IRI, ac:name or name (default robot1)"
    )
    parser.add_argument("--name", help="the agent's name (default KIND.ROBOT, or KIND)")
    parser.add_argument(
        "--time-scale",
        type=float,
        default=1.0,
        metavar="X",
        help="simulated seconds per real second (default 1)",
    )
    parser.add_argument(
        "--tick", type=float, default=0.2, metavar="SECONDS", help="loop period (default 0.2)"
    )
    parser.add_argument(
        "--wait",
        type=float,
        default=30.0,
        metavar="SECONDS",
        help="how long to wait for a router and the store at start (default 30)",
    )
    parser.add_argument(
        "--lifespan",
        type=_lifespan,
        metavar="DURATION",
        help="the values this agent writes expire DURATION (500ms, 5s, 2m) after it stops "
        "renewing them, i.e. after it dies (default: permanent)",
    )
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    cls.add_arguments(parser)
    return parser


def _lifespan(text: str) -> float | None:
    try:
        return check_lifespan(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def run_agent(cls: type[Agent], argv: Sequence[str] | None = None, prog: str | None = None) -> int:
    """Run an agent until SIGINT or SIGTERM; return the exit code (`prog`: see `build_parser`)."""
    args = build_parser(cls, prog).parse_args(argv)
    logging.basicConfig(
        stream=sys.stderr,
        level=[logging.INFO, logging.DEBUG][min(args.verbose, 1)],
        format="%(asctime)s %(name)s %(levelname)s %(message)s",
        force=True,
    )
    agent = cls(args)
    with on_stop_signals(agent.stop):
        try:
            agent.setup()
            freeze_startup()
            agent.run()
            agent.log.info("stopping")
            return 0
        except SpaceError as exc:
            agent.log.error("%s", exc)
            return 1
        finally:
            agent.shutdown()
