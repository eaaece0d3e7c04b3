"""`tspace agent NAME ...`: run one of the robot's agents, as `python -m agents.NAME` does."""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import pkgutil
import re
from pathlib import Path

ORDER = 90
_MAIN = re.compile(r"^def main\(", re.MULTILINE)


def agent_names() -> tuple[str, ...]:
    """Return the modules of `agents` that run as a process: those defining `main`.

    Found from the sources, not imported, so that `tspace --help` stays fast and a
    new agent module needs no second list here.
    """
    spec = importlib.util.find_spec("agents")
    if spec is None or not spec.submodule_search_locations:
        return ()
    names = []
    for info in pkgutil.iter_modules(spec.submodule_search_locations):
        if info.ispkg or info.name.startswith("_"):
            continue
        path = Path(info.module_finder.path) / f"{info.name}.py"  # type: ignore[union-attr]
        if _MAIN.search(path.read_text(encoding="utf-8")):
            names.append(info.name)
    return tuple(sorted(names))


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
    module = importlib.import_module(f"agents.{args.agent}")
    return int(module.main(args.options))
