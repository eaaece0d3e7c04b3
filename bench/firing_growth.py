"""Split the growth of the cost per firing with the number of rules into its causes.

The update of `rules_scaling` (battery -> very low, N rules each firing once) costs
more per firing at 2,000 rules than at 200. For each size N this measures, on the
CPU clock, with the collector as the reasoner agent runs it (start frozen):

- the Python calls per firing (cProfile's count, one update): equal at every N means
  no more rules woken per triple, no longer bucket or agenda walks; and the bytecodes
  per firing (`sys.settrace`'s opcode events, one update): the interpreter's work,
  which the machine's load does not move;
- the garbage collector's share: the collections of each generation during the
  update and their CPU time (`gc.callbacks`), per firing;
- with max(N) rules loaded, an update where only min(N) of them fire (the others'
  settings are "low" already, so their joins run and stop at `notEqual`): its cost
  per firing apart from the collector, beside min(N) rules firing in an engine of
  min(N) rules and max(N) in max(N). The first step is what more rules loaded cost
  a firing, the second what a bigger update costs it (more live objects than the
  caches hold).

Run: python bench/firing_growth.py [--runs 20] [--rounds 2] [--sizes 200 2000] [--old DIR] [--json]

`--old DIR` measures the checkout in DIR (with its own .venv) round by round with this one.
"""

from __future__ import annotations

import argparse
import cProfile
import gc
import json
import pstats
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import FrameType

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _output import bench_parser, parse, print_table
from rdflib import Literal
from rules_scaling import (
    AC,
    BATTERY_LOW,
    BATTERY_NORMAL,
    as_the_reasoner_runs,
    prepared_engine,
    run_child,
)


def settings(n: int, value: str) -> list:
    return [(AC.robot1_base, AC[f"setting_{i}"], Literal(value)) for i in range(n)]


def measure(rules: int, firing: int, runs: int) -> dict[str, float]:
    """Time the update on an engine of `rules` rules of which `firing` fire; split out the gc."""
    engine = prepared_engine(rules)
    lows, normals = settings(rules, "low"), settings(rules, "normal")
    # Before each update: the battery normal, the first `firing` settings normal, the rest low.
    ready = (
        [BATTERY_NORMAL, *normals[:firing], *lows[firing:]],
        [BATTERY_LOW, *lows[:firing], *normals[firing:]],
    )
    spent, collections = [0.0], [0, 0, 0]
    started = [0.0]

    def watch(phase: str, info: dict) -> None:
        if phase == "start":
            collections[info["generation"]] += 1
            started[0] = time.process_time()
        else:
            spent[0] += time.process_time() - started[0]

    totals, collected = [], []
    with as_the_reasoner_runs():
        for _ in range(runs):
            engine.apply(added=ready[0], removed=ready[1])
            spent[0] = 0.0
            gc.callbacks.append(watch)
            start = time.process_time()
            delta = engine.apply(added=[BATTERY_LOW], removed=[BATTERY_NORMAL])
            totals.append(time.process_time() - start)
            gc.callbacks.remove(watch)
            collected.append(spent[0])
            if len(delta.firings) != firing:
                raise SystemExit(f"{rules} rules: {len(delta.firings)} firings, not {firing}")
    engine.apply(added=ready[0], removed=ready[1])
    profile = cProfile.Profile()
    profile.enable()
    engine.apply(added=[BATTERY_LOW], removed=[BATTERY_NORMAL])
    profile.disable()
    calls = sum(row[1] for row in pstats.Stats(profile).stats.values())  # type: ignore[attr-defined]
    engine.apply(added=ready[0], removed=ready[1])
    opcodes = bytecodes(lambda: engine.apply(added=[BATTERY_LOW], removed=[BATTERY_NORMAL]))
    per = 1e6 / firing
    apart = [t - c for t, c in zip(totals, collected, strict=True)]
    return {
        "rules": rules,
        "firing": firing,
        "us_per_firing": statistics.median(totals) * per,
        "gc_us_per_firing": statistics.median(collected) * per,
        "no_gc_us_per_firing": statistics.median(apart) * per,
        "calls_per_firing": calls / firing,
        "bytecodes_per_firing": opcodes / firing,
        **{f"gen{g}_per_update": c / runs for g, c in enumerate(collections)},
    }


def bytecodes(action: Callable[[], object]) -> int:
    """Return how many bytecodes the interpreter runs for `action` (Python code only)."""
    count = [0]

    def trace(frame: FrameType, event: str, arg: object) -> Callable:
        frame.f_trace_opcodes = True
        if event == "opcode":
            count[0] += 1
        return trace

    sys.settrace(trace)
    try:
        action()
    finally:
        sys.settrace(None)
    return count[0]


def child(sizes: list[int], runs: int) -> None:
    """Measure every case on this interpreter's `space`; print JSON lines."""
    small, big = min(sizes), max(sizes)
    cases = [(n, n) for n in sizes] + [(big, small)]
    for rules, firing in cases:
        print(json.dumps(measure(rules, firing, runs)), flush=True)


def main(options: argparse.Namespace) -> None:
    codes = {"new": Path(sys.executable)}
    if options.old:
        codes["old"] = options.old / ".venv" / "bin" / "python"
    found: dict[tuple, list[dict]] = {}
    for _ in range(options.rounds):
        for code, python in codes.items():
            for row in run_child(python, options.sizes, options.runs, False, __file__):
                found.setdefault((code, row["rules"], row["firing"]), []).append(row)
    keys = ["us_per_firing", "no_gc_us_per_firing", "gc_us_per_firing", "calls_per_firing"]
    keys += ["bytecodes_per_firing"]
    keys += ["gen0_per_update", "gen1_per_update", "gen2_per_update"]
    print_table(
        "CPU us per firing (median of the rounds' medians); collections per update",
        ["code", "rules", "firing", *(k.replace("_per_", " per ").replace("_", " ") for k in keys)],
        [
            [code, rules, firing, *(statistics.median(r[k] for r in rows) for k in keys)]
            for (code, rules, firing), rows in found.items()
        ],
    )


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=20, help="updates per case and round")
    parser.add_argument("--rounds", type=int, default=2, help="alternations of the codes")
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 2000])
    parser.add_argument("--old", type=Path, help="a checkout (with .venv) to measure beside")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    options = parse(parser)
    if options.child:
        child(options.sizes, options.runs)
    else:
        main(options)
