"""Time one ontology update against the number of rules, as in Table 1 of Azkune et al. 2013.

The paper's set-up: N rules of the shape of its Figure 5 (seven body patterns
and a notEqual, each dropping one triple and asserting its replacement, so the
state keeps its size), N = 1, 20, ..., 200. One measurement times one update
(battery level "normal" -> "very low") until all N conclusions are in the state,
starting from a prepared engine (loaded, then the update reverted untimed),
with the garbage collector as the reasoner agent runs it (start frozen).
Also: an update no rule's trigger matches, with 1,000 rules loaded; and loading
the project's ontology with its OWL RL closure.

Run: python bench/rules_scaling.py [--runs 30] [--no-plot] [--cpu] [--sizes 1 100 200]

`--cpu` times with the process's CPU clock instead of the wall clock: on a machine shared
with other jobs it moves much less, so two checkouts can be compared side by side
(run the script of each, alternately).
"""

from __future__ import annotations

import argparse
import gc
import statistics
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from rdflib import Literal, Namespace

from space import freeze_startup
from space.reasoning import RuleEngine, parse_rules, read_graph
from space.reasoning.builtins import default_registry

try:  # the engine the reasoner agent builds (every rule form); older checkouts: RuleEngine
    from space.reasoning import build_engine, engine_from_files
except ImportError:
    build_engine, engine_from_files = RuleEngine, RuleEngine.from_files  # type: ignore[assignment]

ROOT = Path(__file__).resolve().parent.parent
ONTOLOGY = ROOT / "ontology" / "selfconfig.ttl"
ROBOT = ROOT / "ontology" / "robots" / "hospital.ttl"
OUT = ROOT / "bench" / "out"
AC = Namespace("https://w3id.org/tspace/selfconfig#")
PAPER = {1: 0.112, 20: 0.324, 40: 0.676, 60: 0.815, 80: 0.989, 100: 1.336}
PAPER |= {120: 1.558, 140: 1.989, 160: 2.222, 180: 2.367, 200: 2.471}
BATTERY_NORMAL = (AC.robot1_battery, AC.battery_level, Literal("normal"))
BATTERY_LOW = (AC.robot1_battery, AC.battery_level, Literal("very low"))


def paper_rules(n: int) -> str:
    """Return n rules shaped like the paper's Figure 5, each on its own setting."""
    rules = ["@prefix ac: <https://w3id.org/tspace/selfconfig#>."]
    for i in range(n):
        rules.append(
            f"[bench_rule_{i}: (?robot rdf:type ac:Robot), (?battery rdf:type ac:Battery),"
            " (?robot ac:has_device ?battery), (?mb rdf:type ac:MobileBase),"
            ' (?robot ac:has_device ?mb), (?battery ac:battery_level "very low"),'
            f' (?mb ac:setting_{i} ?value), notEqual(?value, "low")'
            f' -> drop(6), (?mb ac:setting_{i} "low")]'
        )
    return "\n".join(rules)


def prepared_engine(n: int) -> RuleEngine:
    """Build (as the reasoner agent does) and load an engine with n rules, the ontology and
    the paper's robot."""
    rules = parse_rules(paper_rules(n), default_registry(), source=f"<{n} bench rules>")
    engine = build_engine(rules, read_graph([ONTOLOGY]))
    data = read_graph([ROBOT])
    for i in range(n):
        data.add((AC.robot1_base, AC[f"setting_{i}"], Literal("normal")))
    engine.load(data)
    return engine


CLOCK: list[Callable[[], float]] = [time.perf_counter]  # `--cpu`: time.process_time


def timed(action: Callable[[], object]) -> float:
    """Return the seconds one call takes (wall clock, or CPU with `--cpu`)."""
    clock = CLOCK[0]
    start = clock()
    action()
    return clock() - start


@contextmanager
def as_the_reasoner_runs() -> Iterator[None]:
    """Run the block with the garbage collector as the reasoner agent has it.

    The agent freezes what it built at start out of the collector's full walks
    (`space._heap.freeze_startup`), then collects as usual: so here, after the
    engine is prepared. (A full collection before each timed call, as this bench
    did before, leaves the caches cold and adds 0.1 ms at 1 rule, 0.7 at 200.)
    """
    freeze_startup()
    try:
        yield
    finally:
        gc.unfreeze()


def measure_update(n: int, runs: int) -> list[float]:
    """Time the battery update `runs` times on an engine with n rules."""
    engine = prepared_engine(n)
    lows = [(AC.robot1_base, AC[f"setting_{i}"], Literal("low")) for i in range(n)]
    normals = [(AC.robot1_base, AC[f"setting_{i}"], Literal("normal")) for i in range(n)]
    samples = []
    with as_the_reasoner_runs():
        for _ in range(runs):
            samples.append(
                timed(lambda: engine.apply(added=[BATTERY_LOW], removed=[BATTERY_NORMAL]))
            )
            missing = [t for t in lows if t not in engine]
            if missing:
                example = missing[0]
                raise SystemExit(f"{n} rules: {len(missing)} conclusions missing, e.g. {example}")
            engine.apply(added=[BATTERY_NORMAL, *normals], removed=[BATTERY_LOW, *lows])
    return samples


def measure_unrelated(n: int, runs: int) -> list[float]:
    """Time an update that no rule's trigger matches, with n rules loaded."""
    engine = prepared_engine(n)
    samples = []
    with as_the_reasoner_runs():
        for i in range(runs):
            old = (AC.robot1, AC.heartbeat, Literal(i))
            new = (AC.robot1, AC.heartbeat, Literal(i + 1))
            samples.append(timed(lambda old=old, new=new: engine.apply(added=[new], removed=[old])))
    return samples


def measure_load(runs: int) -> list[float]:
    """Time building an engine for the project's ontology and loading the robot."""
    robot = read_graph([ROBOT])

    def build() -> None:
        engine_from_files(rules=[ROOT / "rules" / "paper.rules"], ontology=[ONTOLOGY]).load(robot)

    return [timed(build) for _ in range(runs)]


def row(label: object, samples: list[float], scale: float = 1e3) -> str:
    values = [s * scale for s in samples]
    stats = (
        statistics.mean(values),
        statistics.stdev(values) if len(values) > 1 else 0.0,
        min(values),
        max(values),
        statistics.median(values),
    )
    return f"{label!s:>6} " + " ".join(f"{v:9.3f}" for v in stats)


def plot(results: dict[int, list[float]]) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    OUT.mkdir(parents=True, exist_ok=True)
    sizes = sorted(results)
    figure, axis = plt.subplots(figsize=(7, 4.5))
    axis.plot(
        sorted(PAPER), [PAPER[n] * 1e3 for n in sorted(PAPER)], "o-", label="paper (Jena 2.6.4)"
    )
    medians = [statistics.median(results[n]) * 1e3 for n in sizes]
    axis.plot(sizes, medians, "s-", label="tspace (p50)")
    axis.fill_between(
        sizes,
        [min(results[n]) * 1e3 for n in sizes],
        [max(results[n]) * 1e3 for n in sizes],
        alpha=0.2,
        label="tspace (min-max)",
    )
    axis.set_yscale("log")
    axis.set_xlabel("rules")
    axis.set_ylabel("time per ontology update (ms)")
    axis.set_title("One update (battery -> very low) against the number of rules")
    axis.grid(True, which="both", alpha=0.3)
    axis.legend()
    path = OUT / "rules_scaling.png"
    figure.savefig(path, dpi=120, bbox_inches="tight")
    return path


def main(runs: int, draw: bool, sizes: list[int]) -> None:
    results = {n: measure_update(n, runs) for n in sizes}
    clock = "CPU" if CLOCK[0] is time.process_time else "wall-clock"
    print(f"One update, {clock} times in ms ({runs} runs each); paper's mean in s for comparison")
    print(f"{'rules':>6} {'mean':>9} {'std':>9} {'min':>9} {'max':>9} {'p50':>9} {'paper':>8}")
    for n in sizes:
        print(row(n, results[n]) + (f" {PAPER[n]:8.3f}" if n in PAPER else ""))
    unrelated = measure_unrelated(1000, runs)
    print(f"\nUpdate matching no rule's trigger, 1000 rules loaded (ms, {runs} runs)")
    print(row(1000, unrelated))
    load = measure_load(max(3, runs // 5))
    print("\nBuild engine for ontology/selfconfig.ttl + paper.rules and load hospital.ttl (ms)")
    print(row("load", load))
    if draw and set(results) >= set(PAPER):
        print(f"\nplot: {plot(results)}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=30, help="measurements per size")
    parser.add_argument("--no-plot", action="store_true", help="skip the PNG")
    parser.add_argument("--cpu", action="store_true", help="time CPU, not wall clock")
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=sorted(PAPER), help="rule counts (the paper's)"
    )
    options = parser.parse_args()
    if options.cpu:
        CLOCK[0] = time.process_time
    main(options.runs, not options.no_plot, options.sizes)
