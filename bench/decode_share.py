"""How much of a fleet's traffic one robot's agent decodes (issue 12's figure).

A robot's hw_monitor subscribes as `agents.base.Agent.subscribe` does: its robot's
subjects and a few site predicates (`HwMonitor.shared`), so the router delivers it
the parts of changes on those keys only. In an N-robot fleet where every robot
writes its own readings, it used to decode every robot's changesets, 1/N of which
concern it; the goal is <= 1/10 of that. With `--before DIR` (a worktree of the code
before), that tree's own version of this script runs first, in the same run, on
the same traffic. Medians over `--runs`.

    .venv/bin/python bench/decode_share.py --robots 50 --writes 4 --runs 3 --before /tmp/split-old
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

from _harness import code_env, median, serve
from _output import bench_parser, parse, print_table
from rdflib import Literal

from agents.base import robot_scope
from agents.hw_monitor import HwMonitor
from agents.vocabulary import AC
from space import Change, TripleSpace

DONE = Literal("done")


def one_run(
    endpoint: str, robots: int, writes: int, watched: int, scoped: bool = True
) -> tuple[int, int, int, float]:
    """Return (parts the watched robot's agent decoded, changesets they came from, about it,
    seconds the fleet's writes took); not `scoped`: it subscribes to the whole space."""
    space = f"decode{time.monotonic_ns()}"
    seen: list[Change] = []
    done = threading.Event()
    battery = AC[f"robot{watched}_battery"]

    def on_change(change: Change) -> None:
        if (battery, AC.charge_percent, DONE) in change.added:
            done.set()  # the last write: every part before it has been delivered
        else:
            seen.append(change)

    with (
        TripleSpace.open(endpoint, space=space, agent=f"hw_monitor.robot{watched}") as agent,
        TripleSpace.open(endpoint, space=space, agent="fleet") as fleet,
    ):
        scope = robot_scope(AC[f"robot{watched}"], HwMonitor.shared or ())
        agent.subscribe(None, on_change, scope=scope if scoped else None)
        start = time.perf_counter()
        for step in range(writes):
            for r in range(1, robots + 1):
                fleet.write([(AC[f"robot{r}_battery"], AC.charge_percent, Literal(step))])
        elapsed = time.perf_counter() - start
        fleet.write([(battery, AC.charge_percent, DONE)])
        if not done.wait(60):
            raise SystemExit("the agent never saw the last write")
    mine = sum(1 for c in seen if any(t[0] == battery for t in c.added))
    return len(seen), len({c.id for c in seen}), mine, elapsed


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--robots", type=int, default=50)
    parser.add_argument("--writes", type=int, default=4, help="changesets per robot")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--before", type=Path, help="a worktree of the code before, run first")
    args = parse(parser)
    common = ["--robots", str(args.robots), "--writes", str(args.writes), "--runs", str(args.runs)]
    if args.before is not None:
        print(f"before ({args.before}):", flush=True)
        script = args.before / "bench" / "decode_share.py"
        subprocess.run(
            [sys.executable, str(script), *common], env=code_env(args.before), check=True
        )
        print("after (this tree):", flush=True)
    rows = []
    with serve() as endpoint:
        for scoped in (False, True):
            runs = [
                one_run(endpoint, args.robots, args.writes, 7, scoped) for _ in range(args.runs)
            ]
            rows.append(
                [
                    "robot7's scope" if scoped else "whole space",
                    args.robots * args.writes,
                    *(median([r[i] for r in runs]) for i in range(4)),
                ]
            )
    print_table(
        f"one robot's agent in a {args.robots}-robot fleet ({args.writes} changesets per robot)",
        [
            "subscribed to",
            "written (cs)",
            "decoded (cs)",
            "their changesets (cs)",
            "about robot7 (cs)",
            "writes (s)",
        ],
        rows,
    )


if __name__ == "__main__":
    main()
