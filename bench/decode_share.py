"""How much of a fleet's traffic one robot's agent decodes (issue 12's figure, the baseline).

A robot's hw_monitor subscribes as every agent does (`agents.base.Agent.subscribe`):
the whole space, firing records skipped. In an N-robot fleet where every robot writes
its own readings, it decodes every robot's changesets, of which 1/N concern it. The
goal is <= 1/10 of today's count; this prints today's count and the share that concerns
the robot, median over several runs.

    .venv/bin/python bench/decode_share.py --robots 50 --writes 4 --runs 3
"""

from __future__ import annotations

import argparse
import threading
import time

from _harness import median, print_table, serve
from rdflib import Literal, Namespace

from agents.vocabulary import AC, RECORD_PREFIX
from space import Change, TripleSpace

EX = Namespace("http://example.org/bench/")


def one_run(endpoint: str, robots: int, writes: int, watched: int) -> tuple[int, int]:
    """Return (changesets the watched robot's subscription decoded, those about its robot)."""
    space = f"decode{time.monotonic_ns()}"
    total = robots * writes
    seen, mine = [0], [0]
    done = threading.Event()
    robot = AC[f"robot{watched}_battery"]

    def on_change(change: Change) -> None:
        seen[0] += 1
        if any(t[0] == robot for t in change.added):
            mine[0] += 1
        if seen[0] >= total:
            done.set()

    with (
        TripleSpace.open(endpoint, space=space, agent=f"hw_monitor.robot{watched}") as agent,
        TripleSpace.open(endpoint, space=space, agent="fleet") as fleet,
    ):
        agent.subscribe(None, on_change, skip_subjects=RECORD_PREFIX)
        for step in range(writes):
            for r in range(1, robots + 1):
                fleet.write([(AC[f"robot{r}_battery"], AC.charge_percent, Literal(step))])
        done.wait(60)
    return seen[0], mine[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robots", type=int, default=50)
    parser.add_argument("--writes", type=int, default=4, help="changesets per robot")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    with serve() as endpoint:
        runs = [one_run(endpoint, args.robots, args.writes, 7) for _ in range(args.runs)]
    decoded = median([r[0] for r in runs])
    concerning = median([r[1] for r in runs])
    print_table(
        f"one robot's agent in a {args.robots}-robot fleet ({args.writes} changesets per robot)",
        ["changesets written", "decoded by robot7's agent", "about robot7", "target (1/10)"],
        [[args.robots * args.writes, decoded, concerning, decoded / 10]],
    )


if __name__ == "__main__":
    main()
