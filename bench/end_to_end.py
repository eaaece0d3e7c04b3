"""End to end: from the hw_monitor writing "battery very low" to the robot having acted on it.

Every part is its own process on loopback, as `tspace up` runs them: `tspace serve`
(router + store), the reasoner, the hw_monitor, the nav_monitor and the behaviour
agent. The bench writes a charge of 5 % into the space; the hw_monitor adopts it
and writes the battery level "very low" (the start); the reasoner concludes the
paper's three things; then each agent that acts on one reports it:

- behaviour: takes up GoingToDock (its changeset with the new `ac:task_started`);
- nav: applies the low maximum speed (its `ac:speed_limit` 0.3 m/s);
- hw: touch screen, speakers and microphone are in stand-by (their `ac:actual_mode`).

Latency (milliseconds) is from the start, the hw_monitor's HLC timestamp on its
changeset (Zenoh's, from the wall clock all processes on a host share), to the moment
the last of the three has *acted*: its changeset committed by the store and published,
stamped on the wall clock when the bench's plain Zenoh subscriber on `@/changes`
receives it. The reasoner's column is stamped the same way. The bench follows the
space in the changesets' own N-Triples texts (msgpack, no rdflib term), so that it
takes as little CPU as it can from the processes it measures. The simulated drivers
switch modes at once here (`--switch-delay 0`): what is measured is the software, not
a simulated power-up. Each run is undone before the next (charge back to 60 %, task
back to Idle).

Three rule sets: the project's (rules/selfconfig.rules); the same plus N (default 200)
rules shaped like the paper's Table 1 rules (bench/rules_scaling.py makes them), which
the update triggers but which find none of their settings on this robot ("loaded");
and the same with the settings, so that all N conclude, as in the paper's Table 1, and
their conclusions travel through the store to every agent ("firing").

The paper (Jena 2.6.4 on a 2010 PC) reports seconds per update: its column is in
milliseconds here (2.471 s at 200 rules = 2,471 ms).

Run: python bench/end_to_end.py [--runs 100] [--extra-rules 200] [--old TREE] [--json]
[--no-plot]. `--old TREE` runs the store and the agents from another source tree (a
worktree of the code before) too, rule set by rule set in turn, the bench's own client
staying this tree's; `--json` prints one JSON object per line per case
(`{"case": ..., "p50_ms": ..., "p99_ms": ...}`) after the table.
"""

from __future__ import annotations

import json
import queue
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import msgpack
import zenoh
from _harness import code_env, cpu_seconds, median, percentile, reap, serve_process
from _output import bench_parser, parse, png, print_table
from rdflib import Graph, Literal, Namespace, URIRef
from rules_scaling import PAPER, paper_rules

from space import TripleSpace, load_identity
from space.changeset import hlc_key
from space.terms import to_nt

ROOT = Path(__file__).resolve().parent.parent
AC = Namespace("https://w3id.org/tspace/selfconfig#")
SPACE = "e2e"
ROBOT, BATTERY, BASE = AC.robot1, AC.robot1_battery, AC.robot1_base
INTERACTION = (AC.robot1_screen, AC.robot1_speakers, AC.robot1_microphone)
HW, NAV, BEHAVIOR = "hw_monitor.robot1", "nav_monitor.robot1", "behavior.robot1"
ACTORS = ("behaviour", "nav", "hw")
STAGES = ("reasoner built", "reasoner", *ACTORS)  # the table's p50 columns, in path order


@dataclass(frozen=True)
class RuleSet:
    """The rules the reasoner runs: the project's, plus `extra` paper-shaped ones.

    With `firing`, the robot has each extra rule's setting, so each concludes.
    """

    extra: int = 0
    firing: bool = False
    target: str = ""

    @property
    def label(self) -> str:
        """Return the rule set's name in the table."""
        if not self.extra:
            return "project"
        return f"project + {self.extra} {'firing' if self.firing else 'loaded'}"

    @property
    def settings(self) -> list[URIRef]:
        """Return the base's properties the extra rules set (when they fire)."""
        return [AC[f"setting_{i}"] for i in range(self.extra)] if self.firing else []


def agent_commands(
    endpoint: str, rules: list[Path], secure: Path | None = None
) -> dict[str, list[str]]:
    """Return the command line of each agent process of the bench's robot (`--secure`: mTLS)."""
    common = ["--connect", endpoint, "--space", SPACE, "--robot", "robot1"]
    if secure is not None:
        common += ["--secure", str(secure)]
    reasoner = [arg for path in rules for arg in ("--rules", str(path))]
    return {
        "reasoner": ["agents.reasoner", *common, *reasoner],
        "hw_monitor": ["agents.hw_monitor", *common, "--switch-delay", "0"],
        # The robot drives to its dock so slowly that it is still on its way after every run.
        "nav_monitor": ["agents.nav_monitor", *common, "--time-scale", "0.001"],
        "behavior": ["agents.behavior", *common],
    }


@contextmanager
def agents(
    commands: dict[str, list[str]], logs: Path, code: Path | None = None
) -> Iterator[dict[str, int]]:
    """Run the agent processes (stderr to `logs/NAME.log`), from `code` if given; stop them.

    Yields each agent's pid by name.
    """
    procs: list[subprocess.Popen[bytes]] = []
    try:
        for name, argv in commands.items():
            with open(logs / f"{name}.log", "wb") as log:
                procs.append(
                    subprocess.Popen(
                        [sys.executable, "-m", *argv],
                        cwd=code or ROOT,
                        stderr=log,
                        env=code_env(code),
                    )
                )
        yield {name: proc.pid for name, proc in zip(commands, procs, strict=True)}
    finally:
        for proc in procs:
            proc.terminate()
        reap(procs)


def nt(term: object) -> str:
    """Return a term's N-Triples text, the form the bench compares changes in."""
    return to_nt(term)  # type: ignore[arg-type]


TEXT = {
    name: nt(term)
    for name, term in {
        "robot": ROBOT,
        "battery": BATTERY,
        "base": BASE,
        "battery_level": AC.battery_level,
        "very low": Literal("very low"),
        "normal": Literal("normal"),
        "task_started": AC.task_started,
        "current_task": AC.current_task,
        "task_idle": AC.task_idle,
        "target_place": AC.target_place,
        "speed_limit": AC.speed_limit,
        "actual_mode": AC.actual_mode,
        "stand-by": Literal("stand-by"),
        "active": Literal("active"),
    }.items()
}
DEVICES = [nt(d) for d in INTERACTION]


def number(text: str | None) -> float | None:
    """Return the number an N-Triples literal's text holds, None if none."""
    if text is None or not text.startswith('"'):
        return None
    try:
        return float(text[1 : text.index('"', 1)])
    except ValueError:
        return None


def seconds(wire: dict) -> float:
    """Return the wall-clock time of a changeset's HLC timestamp, in seconds."""
    return hlc_key(wire["ts"])[0] / 2**32


@dataclass
class Run:
    """One very low battery, followed from the hw_monitor's write to the agents' published acts.

    Fed the changesets the store published (their wire maps, N-Triples texts: the
    bench makes no rdflib term while it measures) with when each arrived (s).
    """

    start: float | None = None
    start_id: str = ""
    reasoner: float | None = None
    acted: dict[str, float] = field(default_factory=dict)
    built: dict[str, float] = field(default_factory=dict)  # HLC time of what was published
    standby: dict[str, tuple[float, float]] = field(default_factory=dict)

    def feed(self, wire: dict, arrival: float) -> None:
        """Take note of what a published changeset says about this run."""
        agent, t = wire.get("agent"), TEXT
        added = [tuple(x) for x in wire.get("add") or ()]
        if self.start is None:
            if agent == HW and (t["battery"], t["battery_level"], t["very low"]) in added:
                self.start, self.start_id = seconds(wire), wire["id"]
            return
        if agent == "reasoner" and wire.get("cause") == self.start_id:
            self.reasoner, self.built["reasoner"] = arrival, seconds(wire)
        elif agent == BEHAVIOR and any(p == t["task_started"] for _, p, _ in added):
            self._acted("behaviour", wire, arrival)
        elif agent == NAV and any(
            s == t["base"] and p == t["speed_limit"] and number(o) == 0.3 for s, p, o in added
        ):
            self._acted("nav", wire, arrival)
        elif agent == HW:
            for device in DEVICES:
                if (device, t["actual_mode"], t["stand-by"]) in added:
                    self.standby.setdefault(device, (arrival, seconds(wire)))
            if len(self.standby) == len(DEVICES) and "hw" not in self.acted:
                self.acted["hw"], self.built["hw"] = max(self.standby.values())

    def _acted(self, name: str, wire: dict, arrival: float) -> None:
        if name not in self.acted:
            self.acted[name], self.built[name] = arrival, seconds(wire)

    @property
    def done(self) -> bool:
        """Return whether all three agents have acted."""
        return len(self.acted) == len(ACTORS)

    def latencies(self) -> dict[str, float]:
        """Return ms from the start to each stage, and of the hops through the store.

        `reasoner built`: the reasoner's answer made (its HLC time); `reasoner`: that
        answer published; each agent's act published, and the `last` of them;
        `answer hop` and `last hop`: from a changeset made to it published (send,
        commit, publish) for the reasoner's answer and the last act.
        """
        assert self.start is not None and self.reasoner is not None
        last = max(ACTORS, key=lambda name: self.acted[name])
        out = {"reasoner built": self.built["reasoner"] - self.start}
        out["reasoner"] = self.reasoner - self.start
        out |= {name: self.acted[name] - self.start for name in ACTORS}
        out["last"] = self.acted[last] - self.start
        out["answer hop"] = self.reasoner - self.built["reasoner"]
        out["last hop"] = self.acted[last] - self.built[last]
        return {name: value * 1e3 for name, value in out.items()}


class Observer:
    """The bench's copy of the space, in N-Triples texts, from what the store publishes.

    A plain Zenoh subscriber on `@/changes` stamps each changeset's arrival in its
    callback; the bench's thread decodes them (msgpack only) in seq order. So the
    bench competes with the processes it measures as little as it can.
    """

    def __init__(self, session: zenoh.Session) -> None:
        self.written: dict[str, int] = {}  # changesets published, by writer
        self.state: dict[tuple[str, str], set[str]] = {}  # (s, p) -> objects
        self.seq = 0
        self._raw: queue.SimpleQueue[tuple[float, bytes]] = queue.SimpleQueue()
        self._sub = session.declare_subscriber(
            f"tspace/{SPACE}/@/changes",
            lambda sample: self._raw.put((time.time(), sample.payload.to_bytes())),
        )

    def load(self, ts: TripleSpace) -> None:
        """Start from the space's state (read after subscribing: no change falls between)."""
        graph, self.seq = ts.snapshot()
        for s, p, o in graph:
            self.state.setdefault((nt(s), nt(p)), set()).add(nt(o))

    def close(self) -> None:
        """Stop watching."""
        self._sub.undeclare()

    def value(self, s: str, p: str) -> str | None:
        """Return the one object of (s, p), None if none (or several)."""
        objects = self.state.get((s, p), set())
        return next(iter(objects)) if len(objects) == 1 else None

    def until(
        self,
        condition: Callable[[], bool],
        what: str,
        timeout: float = 30.0,
        run: Run | None = None,
    ) -> None:
        """Apply published changes (feeding `run`) until `condition()` holds.

        Raises:
            SystemExit: it did not hold within `timeout` seconds, or a change went missing.
        """
        deadline = time.monotonic() + timeout
        while not condition():
            try:
                arrival, payload = self._raw.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise SystemExit(f"end_to_end: no {what} within {timeout:g} s") from None
            self._take(arrival, payload, run)

    def settle(self, quiet: float = 0.05) -> None:
        """Apply changes until none came for `quiet` seconds: the last run's echoes are over."""
        while True:
            try:
                arrival, payload = self._raw.get(timeout=quiet)
            except queue.Empty:
                return
            self._take(arrival, payload, None)

    def _take(self, arrival: float, payload: bytes, run: Run | None) -> None:
        """Apply one published changeset, in seq order, and feed it to `run`.

        Raises:
            SystemExit: a change before it was not seen.
        """
        wire = msgpack.unpackb(payload)
        if wire["seq"] <= self.seq:
            return  # in the state loaded
        if wire["seq"] != self.seq + 1:
            raise SystemExit(f"end_to_end: change {self.seq + 1} not seen")
        self.seq = wire["seq"]
        self._apply(wire)
        if run is not None:
            run.feed(wire, arrival)

    def _apply(self, wire: dict) -> None:
        agent = wire.get("agent") or ""
        self.written[agent] = self.written.get(agent, 0) + 1
        for s, p, o in wire.get("del") or ():
            self.state.get((s, p), set()).discard(o)
        for s, p, o in wire.get("add") or ():
            self.state.setdefault((s, p), set()).add(o)

    def at_rest(self) -> bool:
        """Return whether the robot is back where every run starts."""
        t = TEXT
        return (
            self.value(t["battery"], t["battery_level"]) == t["normal"]
            and self.value(t["robot"], t["current_task"]) == t["task_idle"]
            and not self.state.get((t["robot"], t["target_place"]))
            and number(self.value(t["base"], t["speed_limit"])) == 0.7
            and all(self.value(d, t["actual_mode"]) == t["active"] for d in DEVICES)
        )


def stage(rule_set: RuleSet) -> Graph:
    """Return the robot of the paper in a room far from its dock, normal battery."""
    graph = Graph()
    for path in ("ontology/selfconfig.ttl", "ontology/robots/hospital.ttl"):
        graph.parse(ROOT / path)
    graph.remove((ROBOT, AC.location, None))
    graph.add((ROBOT, AC.location, AC.therapy_room))
    graph.add((ROBOT, AC.position_x, Literal(14.0)))
    graph.add((ROBOT, AC.position_y, Literal(4.0)))
    for setting in rule_set.settings:
        graph.add((BASE, setting, Literal("normal")))
    return graph


def measure(
    runs: int,
    rule_set: RuleSet,
    logs: Path,
    secure: Path | None = None,
    code: Path | None = None,
) -> tuple[list[dict[str, float]], Load]:
    """Run the robot's processes and time `runs` very low batteries.

    Returns their latencies, and the `Load` of a run (the very low battery and its
    undoing).

    With `secure` (a `tspace certs` directory), every process speaks mTLS as itself
    and the bench as the operator. `code`: the source tree the store and the
    agents run from (default: this one).
    """
    rules = [ROOT / "rules" / "selfconfig.rules"]
    if rule_set.extra:
        rules.append(logs / "extra.rules")
        rules[-1].write_text(paper_rules(rule_set.extra))
    settings = rule_set.settings
    identity = load_identity(secure, "operator") if secure else None
    with (
        serve_process(code, secure=secure) as (endpoint, serve_pid),
        TripleSpace.open(endpoint, space=SPACE, agent="bench", identity=identity) as ts,
    ):
        ts.write(stage(rule_set))
        observer = Observer(ts.session)
        observer.load(ts)
        with agents(agent_commands(endpoint, rules, secure), logs, code) as pids:
            observer.until(
                lambda: (
                    {"reasoner", HW, NAV, BEHAVIOR} <= observer.written.keys()
                    and observer.at_rest()
                ),
                "start of the agents",
            )
            observer.settle()
            pids = {"serve": serve_pid, **pids}
            before = {name: cpu_seconds([pid]) for name, pid in pids.items()}
            published = sum(observer.written.values())
            results = []
            for _ in range(runs):
                run = Run()
                ts.write([(BATTERY, AC.charge_percent, Literal(5))])
                observer.until(lambda run=run: run.done, "reaction to very low", run=run)
                results.append(run.latencies())
                ts.write([(BATTERY, AC.charge_percent, Literal(60))])
                observer.until(
                    lambda: (
                        observer.value(TEXT["battery"], TEXT["battery_level"]) == TEXT["normal"]
                    ),
                    "normal battery",
                )
                ts.apply(
                    [(ROBOT, AC.current_task, AC.task_idle)]
                    + [(BASE, s, Literal("normal")) for s in settings],
                    [(ROBOT, AC.current_task, AC.task_going_to_dock)]
                    + [(BASE, s, Literal("low")) for s in settings],
                )
                observer.until(observer.at_rest, "robot back at rest")
                observer.settle()  # what answers the reset (the reasoner's, the agents') is over
            load = Load(
                {
                    name: (cpu_seconds([pid]) - before[name]) * 1e3 / runs
                    for name, pid in pids.items()
                },
                (sum(observer.written.values()) - published) / runs,
            )
        observer.close()
    return results, load


Results = dict[tuple[str, RuleSet], list[dict[str, float]]]  # (tree, rule set) -> runs


@dataclass(frozen=True)
class Load:
    """What a run (a very low battery and its undoing) cost the processes measured."""

    cpu: dict[str, float]  # CPU ms per run, by process (the store, then each agent)
    changesets: float  # changesets the store published per run


def case(tree: str, rule_set: RuleSet) -> str:
    """Return a case's name: the rule set, and which code ran it when two did."""
    return rule_set.label if not tree else f"{rule_set.label} ({tree})"


def summary(tree: str, rule_set: RuleSet, results: list[dict[str, float]]) -> list[object]:
    """Return one table row: p50 per stage, then p50/p99/max of the last agent, and the paper."""
    last = [r["last"] for r in results]
    return [
        case(tree, rule_set),
        len(results),
        *(median([r[name] for r in results]) for name in STAGES),
        median(last),
        percentile(last, 99),
        max(last),
        median([r["answer hop"] for r in results]),
        median([r["last hop"] for r in results]),
        rule_set.target,
        PAPER[max(1, rule_set.extra)] * 1e3,
    ]


def as_json(tree: str, rule_set: RuleSet, results: list[dict[str, float]]) -> str:
    """Return one case as a JSON line: p50/p99 of the last agent, and each stage's p50 (ms)."""
    last = [r["last"] for r in results]
    line: dict[str, object] = {
        "case": case(tree, rule_set),
        "runs": len(results),
        "p50_ms": round(median(last), 3),
        "p99_ms": round(percentile(last, 99), 3),
        "max_ms": round(max(last), 3),
    }
    line |= {
        f"{name.replace(' ', '_')}_p50_ms": round(median([r[name] for r in results]), 3)
        for name in (*STAGES, "answer hop", "last hop")
    }
    line["paper_ms"] = PAPER[max(1, rule_set.extra)] * 1e3
    return json.dumps(line)


def plot(all_results: Results, path: Path) -> Path:
    """Draw the distribution of the last agent's latency per case, with the paper's."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    figure, axis = plt.subplots(figsize=(7, 4.5))
    for (tree, rule_set), results in all_results.items():
        values = sorted(r["last"] for r in results)
        share = [(i + 1) / len(values) for i in range(len(values))]
        style = "--" if tree == "old" else "-"
        axis.step(values, share, style, where="post", label=f"tspace, {case(tree, rule_set)}")
    extra = max(1, *(r.extra for _, r in all_results))
    for rules in (1, extra):
        axis.axvline(PAPER[rules] * 1e3, linestyle=":", color="grey")
        axis.annotate(
            f"paper (Jena), {rules} rule{'s' * (rules > 1)}: {PAPER[rules] * 1e3:,.0f} ms",
            (PAPER[rules] * 1e3, 0.05),
            rotation=90,
        )
    axis.set_xscale("log")
    axis.set_xlabel('"battery very low" written -> last agent\'s act published (ms, log)')
    axis.set_ylabel("share of runs")
    axis.set_title("End to end, separate processes on loopback")
    axis.grid(True, which="both", alpha=0.3)
    axis.legend(loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=2, fontsize="small")
    figure.savefig(path, dpi=120, bbox_inches="tight")
    return path


def main(
    runs: int, extra: int, draw: Path | None, old: Path | None, as_lines: bool, only: list[str]
) -> None:
    cases = {
        "project": RuleSet(target="p50 <= 3, p99 <= 10"),
        "loaded": RuleSet(extra),
        "firing": RuleSet(extra, firing=True, target="p50 <= 10, p99 <= 25"),
    }
    rule_sets = [cases[name] for name in only or cases]
    trees: list[tuple[str, Path | None]] = [("new", None)]
    if old is not None:
        trees.insert(0, ("old", old.resolve()))
    all_results: Results = {}
    loads: dict[tuple[str, RuleSet], Load] = {}
    with tempfile.TemporaryDirectory(prefix="tspace-e2e-") as tmp:
        for index, rule_set in enumerate(rule_sets):
            for tree, code in trees:  # in turn: a slow spell of a shared machine hits both
                logs = Path(tmp) / f"{index}-{tree}"
                logs.mkdir()
                label = tree if old is not None else ""
                all_results[(label, rule_set)], loads[(label, rule_set)] = measure(
                    runs, rule_set, logs, code=code
                )
    print_table(
        '"battery very low" written by hw_monitor -> acts of behaviour, nav and hw committed '
        f"and published (ms; {runs} runs; p50 = median over runs; paper: Jena, ms per update)",
        [
            "case",
            "runs",
            "reasoner built p50 (ms)",
            "reasoner p50 (ms)",
            "behaviour p50 (ms)",
            "nav p50 (ms)",
            "hw p50 (ms)",
            "last p50 (ms)",
            "last p99 (ms)",
            "last max (ms)",
            "answer hop p50 (ms)",
            "last hop p50 (ms)",
            "target (ms)",
            "paper (ms)",
        ],
        [summary(tree, rule_set, results) for (tree, rule_set), results in all_results.items()],
    )
    processes = list(next(iter(loads.values())).cpu)
    print_table(
        "CPU per run, by process (ms; a run = the very low battery and its undoing; "
        "2 cores = 2 ms of CPU per ms)",
        ["case", *(f"{name} (ms)" for name in processes), "all (ms)", "changesets"],
        [
            [
                case(tree, rule_set),
                *(load.cpu[name] for name in processes),
                sum(load.cpu.values()),
                load.changesets,
            ]
            for (tree, rule_set), load in loads.items()
        ],
    )
    if as_lines:
        for (tree, rule_set), results in all_results.items():
            print(as_json(tree, rule_set, results), flush=True)
    if draw is not None:
        print(f"plot: {plot(all_results, draw)}")


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=100, help="very low batteries per rule set")
    parser.add_argument(
        "--extra-rules",
        type=int,
        default=200,
        metavar="N",
        help="paper-shaped rules beside the project's (default 200)",
    )
    parser.add_argument(
        "--old", type=Path, metavar="TREE", help="also run the store and agents from TREE"
    )
    parser.add_argument(
        "--case",
        action="append",
        choices=["project", "loaded", "firing"],
        help="run only these rule sets (repeatable; default all three)",
    )
    options = parse(parser, own_json=True, own_plot=True)
    main(
        options.runs,
        options.extra_rules,
        png(options, "end_to_end.png"),
        options.old,
        options.json,
        options.case or [],
    )
