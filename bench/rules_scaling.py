"""Time one ontology update against the number of rules, beside Jena 4.5 and the paper's Table 1.

The paper's set-up (Azkune et al. 2013, Table 1): N rules of the shape of its
Figure 5 (seven body patterns and a notEqual, each dropping one triple and
asserting its replacement, so the state keeps its size), N = 1, 20, ..., 200.
One measurement times one update (battery level "normal" -> "very low") and
reading the matches (the mobile base's triples, N of them now "low") on a
prepared engine (loaded, then the update reverted untimed), with the garbage
collector as the reasoner agent runs it (start frozen). Also: an update no
rule's trigger matches, with 1,000 rules loaded; building the project's engine and
an engine for N rules, each the first time in a process and again (a reload: the
compiled rules are reused, `rulecode`); and loading the project's ontology with its
OWL RL closure.

Run: python bench/rules_scaling.py [--runs 30] [--sizes 1 200 1000] [--jena] [--old DIR]
                                   [--rounds 3] [--cpu] [--json] [--no-plot]

`--old DIR` measures the checkout in DIR (with its own .venv) in the same run, round by
round with this one, so that old and new share the machine's moods. `--jena` times the same
update and read on Apache Jena 4.5 (GenericRuleReasoner, FORWARD_RETE) in process, after a
warm-up that leaves its JIT compiled (bench/jena_referee/UpdateTimer.java; Java and Debian's
libapache-jena-java). `--cpu` times with the CPU clock of the thread doing the work instead of
the wall clock: on a machine shared with other jobs it moves much less. `--json` prints one
JSON object per line per case and code instead of the tables. The paper's figures (Jena 2.6.4,
seconds) are shown converted to milliseconds.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from _output import bench_parser, parse, png
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
AC = Namespace("https://w3id.org/tspace/selfconfig#")
PAPER = {1: 0.112, 20: 0.324, 40: 0.676, 60: 0.815, 80: 0.989, 100: 1.336}  # seconds
PAPER |= {120: 1.558, 140: 1.989, 160: 2.222, 180: 2.367, 200: 2.471}
PAPER_LABEL = "paper (Jena 2.6.4, mean)"
BATTERY_NORMAL = (AC.robot1_battery, AC.battery_level, Literal("normal"))
BATTERY_LOW = (AC.robot1_battery, AC.battery_level, Literal("very low"))
UNRELATED_RULES = 1000


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


def paper_data(n: int) -> list:
    """Return the robot of the paper and its n settings (all "normal")."""
    data = list(read_graph([ROBOT]))
    data += [(AC.robot1_base, AC[f"setting_{i}"], Literal("normal")) for i in range(n)]
    return data


def built_engine(n: int) -> RuleEngine:
    """Build an engine with n rules and the ontology, as the reasoner agent does."""
    rules = parse_rules(paper_rules(n), default_registry(), source=f"<{n} bench rules>")
    return build_engine(rules, read_graph([ONTOLOGY]))


def prepared_engine(n: int) -> RuleEngine:
    """Build and load an engine with n rules, the ontology and the paper's robot."""
    engine = built_engine(n)
    engine.load(paper_data(n))
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
    engine is prepared. (A full collection before each timed call leaves the
    caches cold and adds 0.1 ms at 1 rule, 0.7 at 200.)
    """
    freeze_startup()
    try:
        yield
    finally:
        gc.unfreeze()


def measure_update(n: int, runs: int) -> list[float]:
    """Time the battery update and reading the matches `runs` times on an engine with n rules."""
    engine = prepared_engine(n)
    lows = [(AC.robot1_base, AC[f"setting_{i}"], Literal("low")) for i in range(n)]
    normals = [(AC.robot1_base, AC[f"setting_{i}"], Literal("normal")) for i in range(n)]
    low = Literal("low")
    found = [0]

    def update() -> None:
        engine.apply(added=[BATTERY_LOW], removed=[BATTERY_NORMAL])
        found[0] = sum(1 for _, _, o in engine.match(AC.robot1_base, None, None) if o == low)

    samples = []
    with as_the_reasoner_runs():
        for _ in range(runs):
            samples.append(timed(update))
            if found[0] != n:
                raise SystemExit(f"{n} rules: {found[0]} conclusions, not {n}")
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


def measure_builds(n: int, runs: int) -> tuple[list[float], list[float]]:
    """Time building an engine for n rules and the ontology: first in this process, then again."""
    first = [timed(lambda: built_engine(n))]
    return first, [timed(lambda: built_engine(n)) for _ in range(runs)]


def measure_project_builds(runs: int) -> tuple[list[float], list[float]]:
    """Time building the project's engine (paper.rules, the ontology): first, then again."""

    def build() -> None:
        engine_from_files(rules=[ROOT / "rules" / "paper.rules"], ontology=[ONTOLOGY])

    first = [timed(build)]
    return first, [timed(build) for _ in range(runs)]


def measure_load(runs: int) -> list[float]:
    """Time building an engine for the project's ontology and loading the robot."""
    robot = read_graph([ROBOT])

    def build() -> None:
        engine_from_files(rules=[ROOT / "rules" / "paper.rules"], ontology=[ONTOLOGY]).load(robot)

    return [timed(build) for _ in range(runs)]


def child(sizes: list[int], runs: int) -> None:
    """Measure every case on this interpreter's `space`; print raw samples as JSON lines."""
    project, reloads = measure_project_builds(max(2, runs // 5))  # first: nothing compiled yet
    first, again = measure_builds(max(sizes), max(2, runs // 5))
    cases: list[tuple[str, int | None, list[float]]] = [
        ("project build", None, project),
        ("project rebuild", None, reloads),
        ("build", max(sizes), first),
        ("rebuild", max(sizes), again),
    ]
    for n in sizes:
        cases.append(("update", n, measure_update(n, runs)))
    cases.append(("unrelated", UNRELATED_RULES, measure_unrelated(UNRELATED_RULES, runs)))
    cases.append(("load", None, measure_load(max(2, runs // 5))))
    for case, n, samples in cases:
        line = {"case": case, "rules": n, "samples_ms": [s * 1e3 for s in samples]}
        print(json.dumps(line), flush=True)


def run_child(
    python: Path, sizes: list[int], runs: int, cpu: bool, script: str = __file__
) -> list[dict]:
    """Run `script`'s `child` (this one's, or another bench's) under another interpreter
    (another checkout's venv, or this one); return its JSON lines."""
    command = [str(python), script, "--child", "--runs", str(runs), "--sizes", *map(str, sizes)]
    done = subprocess.run(command + ["--cpu"] * cpu, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{python} failed:\n{done.stderr[-3000:]}")
    return [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]


def run_jena(sizes: list[int], runs: int, cpu: bool, work: Path) -> list[dict]:
    """Time the update on Jena 4.5 (bench/jena_referee/UpdateTimer.java), one JVM for all sizes."""
    from jena_referee import classpath

    cp = classpath(work)
    classes = work / "classes"
    if not classes.exists():
        source = ROOT / "bench" / "jena_referee" / "UpdateTimer.java"
        subprocess.run(["javac", "-nowarn", "-cp", cp, "-d", str(classes), source], check=True)
    jobs = []
    ontology = read_graph([ONTOLOGY])
    for n in sizes:
        rules, data = work / f"{n}.rules", work / f"{n}.nt"
        if not data.exists():
            rules.write_text(paper_rules(n))
            graph = read_graph([])
            for t in (*ontology, *paper_data(n)):
                graph.add(t)
            data.write_text(graph.serialize(format="nt", encoding="utf-8").decode())
        warmup = min(2000, max(30, 50_000 // n))  # enough firings for the JIT to settle
        jobs.append(f"{rules}\t{data}\t{n}\t{runs}\t{warmup}\t{'cpu' if cpu else 'wall'}\n")
    (work / "jobs.tsv").write_text("".join(jobs))
    command = ["java", "-cp", f"{classes}:{cp}", "UpdateTimer", str(work / "jobs.tsv")]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"Jena failed:\n{done.stderr[-3000:]}")
    lines = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    return [{"case": "update", "rules": d["rules"], "samples_ms": d["samples_ms"]} for d in lines]


def summary(samples: list[float]) -> dict[str, float]:
    """Return p50, p99, mean, min and max (ms) of samples in ms."""
    p99 = statistics.quantiles(samples, n=100, method="inclusive")[98] if len(samples) > 1 else 0
    return {
        "p50_ms": statistics.median(samples),
        "p99_ms": p99 or samples[0],
        "mean_ms": statistics.mean(samples),
        "min_ms": min(samples),
        "max_ms": max(samples),
        "runs": len(samples),
    }


def collect(codes: dict[str, Callable[[int], list[dict]]], rounds: int) -> dict[tuple, dict]:
    """Run each code's measurements round by round; return samples by (code, case, rules)."""
    found: dict[tuple, list[float]] = {}
    for round_ in range(rounds):
        for code, measure in codes.items():
            for line in measure(round_):
                found.setdefault((code, line["case"], line["rules"]), []).extend(line["samples_ms"])
    return {key: summary(samples) for key, samples in found.items()}


def report(results: dict[tuple, dict], sizes: list[int], as_json: bool, clock: str) -> None:
    """Print the tables (or JSON lines): each case, each code, ratios to the others."""
    codes = sorted({code for code, _, _ in results}, key=["new", "old", "jena"].index)
    lines = []
    for (code, case, n), stats in results.items():
        line = {"case": case, "rules": n, "code": code, **stats, "clock": clock}
        if case == "update":
            line["per_firing_us"] = stats["p50_ms"] / n * 1e3
            if code == "new":
                for other in ("old", "jena"):
                    if (other, case, n) in results:
                        line[f"vs_{other}"] = stats["p50_ms"] / results[(other, case, n)]["p50_ms"]
                if n in PAPER:
                    line["vs_paper"] = stats["p50_ms"] / (PAPER[n] * 1e3)
        lines.append(line)
    lines += [
        {"case": "update", "rules": n, "code": PAPER_LABEL, "mean_ms": PAPER[n] * 1e3}
        for n in sizes
        if n in PAPER
    ]
    if as_json:
        for line in lines:
            print(
                json.dumps({k: round(v, 4) if isinstance(v, float) else v for k, v in line.items()})
            )
        return
    print(f"One update and reading its matches, {clock} ms, p50 (per firing in us); paper in ms")
    header = f"{'rules':>6}"
    for code in codes:
        header += f" {code + ' p50 (ms)':>16} {'(us/firing)':>11}"
    header += f" {'paper (ms)':>10}" + "".join(f" {'new/' + c:>9}" for c in codes[1:])
    print(header + f" {'new/paper':>9}")
    for n in sizes:
        row = f"{n:>6}"
        for code in codes:
            stats = results.get((code, "update", n))
            row += (
                f" {stats['p50_ms']:16.3f} {stats['p50_ms'] / n * 1e3:11.2f}" if stats else " " * 29
            )
        row += f" {PAPER[n] * 1e3:10.0f}" if n in PAPER else " " * 11
        new = results[("new", "update", n)]["p50_ms"]
        for code in codes[1:]:
            other = results.get((code, "update", n))
            row += f" {new / other['p50_ms']:9.3f}" if other else " " * 10
        row += f" {new / (PAPER[n] * 1e3):9.4f}" if n in PAPER else ""
        print(row)
    titles = {
        "unrelated": f"An update no rule's trigger matches, {UNRELATED_RULES} rules loaded",
        "build": f"Build an engine for {max(sizes)} rules + the ontology, first in its process",
        "rebuild": "The same build again in that process (compiled rules reused)",
        "project build": "Build the project's engine (selfconfig.ttl, paper.rules), first",
        "project rebuild": "The same build again (a reload of the same rules: compiled reused)",
        "load": "Build the engine for ontology/selfconfig.ttl + paper.rules, load hospital.ttl",
    }
    for case, title in titles.items():
        print(f"\n{title} ({clock} ms)")
        print(f"{'code':>6} {'p50':>10} {'p99':>10} {'min':>10} {'max':>10} {'runs':>5}")
        for code in codes:
            stats = results.get((code, case, max(sizes) if case in ("build", "rebuild") else None))
            if case == "unrelated":
                stats = results.get((code, case, UNRELATED_RULES))
            if stats:
                values = (stats[k] for k in ("p50_ms", "p99_ms", "min_ms", "max_ms"))
                print(
                    f"{code:>6} " + " ".join(f"{v:10.3f}" for v in values) + f" {stats['runs']:5d}"
                )


def plot(results: dict[tuple, dict], sizes: list[int], path: Path) -> Path:
    """Draw each code's p50 and the paper's mean against the number of rules (log scale)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    figure, axis = plt.subplots(figsize=(7, 4.5))
    paper = [n for n in sizes if n in PAPER] or sorted(PAPER)
    axis.plot(paper, [PAPER[n] * 1e3 for n in paper], "o-", label=PAPER_LABEL)
    labels = {"jena": "Jena 4.5 FORWARD_RETE (p50)", "old": "tspace before (p50)"}
    for code, marker in (("jena", "^-"), ("old", "v--"), ("new", "s-")):
        points = [
            (n, results[(code, "update", n)]["p50_ms"])
            for n in sizes
            if (code, "update", n) in results
        ]
        if points:
            xs, ys = zip(*points, strict=True)
            axis.plot(xs, ys, marker, label=labels.get(code, "tspace (p50)"))
    axis.set_yscale("log")
    axis.set_xlabel("rules")
    axis.set_ylabel("time per ontology update (ms)")
    axis.set_title("One update (battery -> very low) and its matches against the number of rules")
    axis.grid(True, which="both", alpha=0.3)
    axis.legend()
    figure.savefig(path, dpi=120, bbox_inches="tight")
    return path


def main(options: argparse.Namespace) -> None:
    sizes, rounds = sorted(options.sizes), options.rounds
    per_round = math.ceil(options.runs / rounds)
    here = Path(sys.executable)
    codes: dict[str, Callable[[int], list[dict]]] = {
        "new": lambda _: run_child(here, sizes, per_round, options.cpu)
    }
    if options.old:
        old_python = options.old / ".venv" / "bin" / "python"
        codes["old"] = lambda _: run_child(old_python, sizes, per_round, options.cpu)
    with tempfile.TemporaryDirectory() as work:
        if options.jena:
            codes["jena"] = lambda _: run_jena(sizes, per_round, options.cpu, Path(work))
        results = collect(codes, rounds)
    report(results, sizes, options.json, "CPU" if options.cpu else "wall-clock")
    path = png(options, "rules_scaling.png")
    if path is not None:
        plot(results, sizes, path)
        if not options.json:
            print(f"\nplot: {path}")


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=30, help="measurements per case and code")
    parser.add_argument("--rounds", type=int, default=3, help="alternations of the codes")
    parser.add_argument("--cpu", action="store_true", help="time CPU, not wall clock")
    parser.add_argument("--jena", action="store_true", help="time Jena 4.5 on the same update")
    parser.add_argument("--old", type=Path, help="a checkout (with .venv) to measure beside")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=sorted(PAPER), help="rule counts (the paper's)"
    )
    options = parse(parser, own_json=True, own_plot=True)
    if options.cpu:
        CLOCK[0] = time.process_time
    if options.child:
        child(sorted(options.sizes), options.runs)
    else:
        main(options)
