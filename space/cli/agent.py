"""`tspace agent NAME ...`: run one of the robot's agents, as `python -m agents.NAME` does."""

from __future__ import annotations

import argparse
import importlib

ORDER = 90

AGENTS = ("reasoner", "hw_monitor", "nav_monitor", "behavior")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `agent` sub-command."""
    p = sub.add_parser(
        "agent",
        help="run an agent process (reasoner, hw_monitor, nav_monitor, behavior)",
        description="Run one agent until Ctrl-C; `tspace agent NAME --help` lists its options.",
    )
    p.add_argument("agent", choices=AGENTS, help="which agent")
    p.add_argument("options", nargs=argparse.REMAINDER, help="the agent's options")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the agent's `main` with the remaining options; return its exit code."""
    module = importlib.import_module(f"agents.{args.agent}")
    return int(module.main(args.options))
