"""`tspace agent NAME ...`: run one of the robot's agents, as `python -m agents.NAME` does."""

from __future__ import annotations

import argparse
import importlib.metadata

ORDER = 90
AGENTS_GROUP = "tspace.agents"


def agent_entries() -> dict[str, importlib.metadata.EntryPoint]:
    """Return the agents that run as a process, by name: the `tspace.agents` entry points.

    Each names an agent's `main(argv, prog) -> int` (`prog` for its usage line);
    they are loaded only when run, so `tspace --help` stays fast, and a new agent
    (ours or another distribution's) is one line in its `pyproject.toml`.
    """
    return {e.name: e for e in importlib.metadata.entry_points(group=AGENTS_GROUP)}


def agent_names() -> tuple[str, ...]:
    """Return the names `tspace agent` accepts, sorted."""
    return tuple(sorted(agent_entries()))


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `agent` sub-command."""
    names = agent_names()
    p = sub.add_parser(
        "agent",
        help=f"run an agent process ({', '.join(names)})",
        description="Run one agent until Ctrl-C; `tspace agent NAME --help` lists its options.",
    )
    p.add_argument("agent", choices=names, help="which agent")
    p.add_argument("options", nargs=argparse.REMAINDER, help="the agent's options")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the agent's `main` with the remaining options; return its exit code."""
    main = agent_entries()[args.agent].load()
    return int(main(args.options, prog=f"tspace agent {args.agent}"))
