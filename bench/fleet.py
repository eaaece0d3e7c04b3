"""Benchmark a fleet sharing one space: latency against fleet size, sustained load, recovery.

Run: python bench/fleet.py [--runs 3] [--seconds 60] [--robots 200] [--cut-hz 1 10]
[--old TREE] [--json] [--no-recovery] [--no-plot]

1. Update latency: a robot's battery turns "very low" (or back to "normal"), and
   the time until the reasoner's conclusions are applied by the store, for
   fleets of 1, 10, 25 and 50 robots (`agents.sim.fleet`, `rules/fleet.rules`),
   one change at a time, after every robot went through two such cycles.
2. Sustained load: 200 robots (`--robots`) each writing a sensor change at 10 Hz
   for `--seconds` (2,000 changesets/s); every 20th change of a robot is a
   battery change the rules answer. Latency of those answers (sent -> the
   reasoner's answer committed and published), changes lost, the reasoner's RSS.
3. Recovery (root only): store on host a, robots' writes through host b, the
   reasoner on host c (`tests/netns.py`); c's link is cut for 5 s while the
   fleet writes at `--cut-hz` per robot; the time from restoring the link until
   c has every change published before and the reasoner has answered every
   battery change written before. With the kernel's TCP defaults, and with
   `net.ipv4.tcp_rto_max_ms=1000` on every host where the kernel has it.

The reasoner is the real `python -m agents.reasoner` process; one process plays
every robot's sensors through the library (what a robot's hw_monitor does), and
a plain Zenoh subscriber records what the store publishes (decoded after the
run, so that watching costs the run nothing). Figures are medians over runs, in
milliseconds unless a header says otherwise. `--old TREE` runs the store and the
reasoner of the update-latency and sustained measures from another source tree too
(a worktree of the code before), in turn with this one; `--json` prints one JSON
object per line per case (`{"case": ..., "p50_ms": ..., "p99_ms": ...}`).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from _fleet import REPO, RULES, Fleet, Observer, describe, reasoner_argv, rss_mb, stop_process
from _harness import code_env, median, percentile, serve_process
from _output import bench_parser, parse, png, print_table

from space import TripleSpace

sys.path.insert(0, str(REPO / "tests"))  # the network-namespace harness
from netns import Network, netns_unavailable

SIZES = (1, 10, 25, 50)
# Battery cycles (very low, normal) of every robot not counted: a robot's first "very low"
# sends it to a dock, a bigger answer than the ones after, so the changes measured are of
# the same kind whatever the fleet's size.
WARMUP_CYCLES = 2
DRAIN = 120.0  # seconds the sustained run waits, after the fleet stops, for the last changes


@contextmanager
def fleet_with_reasoner(
    space: str, count: int, log: Path, code: Path | None = None
) -> Iterator[tuple[Observer, Fleet, subprocess.Popen]]:
    """Serve a space of `count` robots with a reasoner process that has answered its load.

    Yields the observer of what the store publishes, the fleet's sensors and the
    reasoner; the reasoner, the observer and the server are stopped on exit.
    `code`: the source tree the store and the reasoner run from (default this one).
    """
    with (
        serve_process(code) as (endpoint, _pid),
        TripleSpace.open(endpoint, space=space, agent="fleet") as ts,
    ):
        obs = Observer(ts.session, space)
        site = describe(ts, count)
        with open(log, "ab") as out:
            reasoner = subprocess.Popen(
                reasoner_argv(endpoint, space),
                cwd=code or REPO,
                stderr=out,
                env=code_env(code),
            )
        try:
            obs.wait_answer()
            yield obs, Fleet(ts, site, count), reasoner
        finally:
            stop_process(reasoner)
            obs.close()


def update_latency(count: int, samples: int, log: Path, code: Path | None = None) -> list[float]:
    """Return the seconds from a battery change to the reasoner's answer, one at a time."""
    with fleet_with_reasoner(f"fleet{count}", count, log, code) as (obs, fleet, _reasoner):
        latencies = []
        warmup = WARMUP_CYCLES * 2 * count
        for i in range(warmup + samples):
            cid = fleet.battery(i % count)
            if not obs.wait(lambda: cid in obs.answered, 10):  # noqa: B023
                raise TimeoutError(f"no answer to battery change {i} of {count} robots")
            if i >= warmup:
                latencies.append(obs.answered[cid] - fleet.sent[cid])
        return latencies


def sustained(seconds: float, robots: int, hz: float, log: Path, code: Path | None = None) -> dict:
    """Run the fleet at full rate for `seconds`; return rate, losses, latencies, RSS."""
    with fleet_with_reasoner("sustained", robots, log, code) as (obs, fleet, reasoner):
        rss: list[tuple[float, float]] = []  # (seconds into the run, MB)
        done = threading.Event()
        start = time.monotonic()

        def sample() -> None:
            while True:
                rss.append((time.monotonic() - start, rss_mb(reasoner.pid)))
                if done.wait(1.0):
                    return

        sampler = threading.Thread(target=sample)
        sampler.start()
        try:
            rate = fleet.play(seconds, robots * hz)
            sent, markers = fleet.sent, fleet.markers
            played = time.monotonic()
            # A saturated store drains its backlog after the fleet stops: what has not
            # arrived within DRAIN seconds counts as lost.
            obs.wait(
                lambda: sent.keys() <= obs.arrived.keys() and markers.keys() <= obs.answered.keys(),
                DRAIN,
            )
            drained = time.monotonic() - played
        finally:
            done.set()
            sampler.join()
    answers = sorted((t, obs.answered[c] - t) for c, t in markers.items() if c in obs.answered)
    applied = [obs.arrived[c] - t for c, t in sent.items() if c in obs.arrived]
    seqs = sorted(obs.at_seq)
    return {
        "rate": rate,
        "drain": drained,
        "sent": len(sent),
        "lost": len(sent) - len(applied),
        "seq_gaps": seqs[-1] - seqs[0] + 1 - len(seqs),
        "unanswered": len(markers) - len(answers),
        "answers": answers,
        "applied_p99": percentile(applied, 99),
        "rss": rss,
    }


def recovery(robots: int, hz: float, cut: float, sysctls: dict[str, str]) -> dict:
    """Cut the reasoner's host off for `cut` seconds under load; return the catch-up times."""
    space = "recovery"
    with (
        tempfile.TemporaryDirectory(prefix="fleet", dir="/tmp") as tmp,
        Network(["a", "b", "c"], Path(tmp), sysctls) as net,
    ):
        a, b, c = net["a"], net["b"], net["c"]
        a.serve()
        b.serve(store=False, connect=[a])
        c.serve(store=False, connect=[a, b])
        with (
            TripleSpace.open(b.control, space=space, agent="fleet") as ts,
            TripleSpace.open(a.control, space=space) as at_a,
            TripleSpace.open(c.control, space=space) as at_c,
        ):
            obs_a, obs_c = Observer(at_a.session, space), Observer(at_c.session, space)
            site = describe(ts, robots)
            c.agent("reasoner", space=space, args=["--rules", str(RULES)])
            obs_a.wait_answer()
            fleet = Fleet(ts, site, robots)
            stop = threading.Event()
            writer = threading.Thread(target=fleet.play, args=(3600, robots * hz, stop))
            writer.start()
            try:
                time.sleep(2.0)  # the fleet at work before the cut
                with c.outage(cut):
                    pass
                restored = time.monotonic()
                obs_a.drain()
                target = obs_a.last_seq
                before = [cid for cid, t in list(fleet.markers.items()) if t < restored]
                caught_up = obs_c.wait(lambda: obs_c.last_seq >= target, 30)
                answered = obs_a.wait(lambda: all(x in obs_a.answered for x in before), 30)
            finally:
                stop.set()
                writer.join()
            if not (caught_up and answered):
                raise TimeoutError("c or the reasoner did not catch up within 30 s")
            obs_c.wait(lambda: fleet.sent.keys() <= obs_c.arrived.keys(), 10)
            on_c = min(t for seq, t in obs_c.at_seq.items() if seq >= target) - restored
            reasoned = max(obs_a.answered[x] for x in before) - restored
            obs_a.close()
            obs_c.close()
    return {
        "c": on_c,
        "reasoner": reasoned,
        "recovery": max(on_c, reasoned),
        "missed_on_c": len(fleet.sent.keys() - obs_c.arrived.keys()),
    }


def plot(sizes: dict[int, list[list[float]]], load: dict, cuts: list[list], path: Path) -> Path:
    """Draw latency against fleet size, the sustained run, and the recoveries."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    figure, (left, middle, right) = plt.subplots(1, 3, figsize=(17, 4.8), layout="constrained")
    counts = sorted(sizes)
    for q, style in ((50, "o-"), (99, "s--")):
        ms = [median([percentile(run, q) for run in sizes[n]]) * 1e3 for n in counts]
        left.plot(counts, ms, style, label=f"p{q}")
    base = median([percentile(run, 50) for run in sizes[counts[0]]]) * 1e3
    left.axhline(1.5 * base, color="grey", linestyle=":", label="1.5 x p50 at 1 robot")
    left.set(xlabel="robots", ylabel="battery change -> conclusions published (ms)")
    left.set_title("Update latency against fleet size")
    left.legend()
    start = load["answers"][0][0]
    times = [t - start for t, _ in load["answers"]]
    middle.plot(times, [x * 1e3 for _, x in load["answers"]], ".", markersize=2, label="answer")
    middle.axhline(20, color="grey", linestyle=":", label="p99 target, 20 ms")
    middle.set(xlabel="seconds into the run", ylabel="battery change -> answer published (ms)")
    middle.set_title(f"{load['robots']} robots x {load['hz']:g} Hz")
    memory = middle.twinx()
    memory.plot([t for t, _ in load["rss"]], [m for _, m in load["rss"]], "r-", label="RSS")
    memory.set_ylabel("reasoner RSS (MB)")
    memory.set_ylim(0, max(m for _, m in load["rss"]) * 1.3)
    middle.legend(loc="upper left")
    memory.legend(loc="upper right")
    if cuts:
        labels = [row[0].replace("=", "=\n") + f"\n{row[1]:g}/s" for row in cuts]
        right.bar(range(len(cuts)), [row[4] for row in cuts], tick_label=labels)
        right.tick_params(axis="x", labelsize=8)
        right.axhline(2.0, color="grey", linestyle=":", label="2 s")
        right.legend()
    right.set(ylabel="seconds after the link is back (median)")
    right.set_title("Recovery after a 5 s link cut")
    figure.savefig(path, dpi=120, bbox_inches="tight")
    return path


def main(args: argparse.Namespace) -> None:
    log = Path(tempfile.mkdtemp(prefix="fleet-bench-")) / "reasoner.log"
    print(f"reasoner logs: {log}", flush=True)
    trees: list[tuple[str, Path | None]] = [("", None)]
    if args.old is not None:
        trees = [("old", args.old.resolve()), ("new", None)]
    lines: list[dict] = []  # the --json cases
    counts = args.sizes
    sizes: dict[tuple[str, int], list[list[float]]] = {(t, n): [] for t, _ in trees for n in counts}
    for _ in range(args.runs):  # sizes and trees in turn: a slow spell hits them all
        for n in counts:
            for tree, code in trees:
                sizes[(tree, n)].append(update_latency(n, args.samples, log, code))
    rows = []
    for tree, _code in trees:
        if not counts:
            break
        base = median([percentile(run, 50) for run in sizes[(tree, counts[0])]])
        for n in counts:
            p50 = median([percentile(run, 50) for run in sizes[(tree, n)]])
            p99 = median([percentile(run, 99) for run in sizes[(tree, n)]])
            rows.append([tree or "-", n, p50 * 1e3, p99 * 1e3, p50 / base])
            case = f"update, {n} robots" + (f" ({tree})" if tree else "")
            lines.append({"case": case, "p50_ms": p50 * 1e3, "p99_ms": p99 * 1e3})
    if rows:
        print_table(
            "Update latency: battery change -> the reasoner's conclusions committed and published "
            f"(median of {args.runs} runs)",
            ["code", "robots", "p50 (ms)", "p99 (ms)", "p50 / p50 at 1 robot"],
            rows,
        )

    loads = {}
    for tree, code in trees:
        load = loads[tree] = sustained(args.seconds, args.robots, args.hz, log, code)
        load.update(robots=args.robots, hz=args.hz)
    rows = []
    for tree, load in loads.items():
        latencies = [x for _, x in load["answers"]]
        rss = load["rss"]
        at_10 = next((m for t, m in rss if t >= 10), rss[-1][1])
        p50, p99 = percentile(latencies, 50) * 1e3, percentile(latencies, 99) * 1e3
        rows.append(
            [
                tree or "-",
                load["rate"],
                load["sent"],
                load["lost"],
                load["drain"],
                load["seq_gaps"],
                load["unanswered"],
                p50,
                p99,
                load["applied_p99"] * 1e3,
                rss[0][1],
                at_10,
                rss[-1][1],
            ]
        )
        case = f"sustained, {args.robots} robots x {args.hz:g} Hz" + (f" ({tree})" if tree else "")
        lines.append(
            {
                "case": case,
                "p50_ms": p50,
                "p99_ms": p99,
                "rate_per_s": load["rate"],
                "sent": load["sent"],
                "lost": load["lost"],
                "drain_s": load["drain"],
                "unanswered": load["unanswered"],
            }
        )
    print_table(
        f"Sustained load: {args.robots} robots x {args.hz:g} Hz for {args.seconds:g} s "
        "(answer: battery change sent -> the reasoner's answer published; applied: a "
        "sensor change sent -> published)",
        [
            "code",
            "changesets/s",
            "sent (changesets)",
            "lost (changesets)",
            "drained after (s)",
            "seq gaps (count)",
            "unanswered (changes)",
            "answer p50 (ms)",
            "answer p99 (ms)",
            "applied p99 (ms)",
            "RSS start (MB)",
            "RSS at 10 s (MB)",
            "RSS end (MB)",
        ],
        rows,
    )
    load = loads[trees[-1][0]]

    cuts: list[list] = []
    reason = netns_unavailable() if args.recovery else "--no-recovery"
    if reason is None:
        settings: list[tuple[str, dict[str, str]]] = [("kernel defaults", {})]
        if Path("/proc/sys/net/ipv4/tcp_rto_max_ms").exists():
            settings.append(("tcp_rto_max_ms=1000", {"net.ipv4.tcp_rto_max_ms": "1000"}))
        for label, sysctls in settings:
            for hz in args.cut_hz:
                runs = [recovery(args.robots, hz, 5.0, sysctls) for _ in range(args.runs)]
                cuts.append(
                    [label, args.robots * hz]
                    + [median([r[k] for r in runs]) for k in ("c", "reasoner", "recovery")]
                    + [max(r["recovery"] for r in runs), sum(r["missed_on_c"] for r in runs)]
                )
                lines.append(
                    {"case": f"recovery, {label}, {args.robots * hz:g}/s", "p50_s": cuts[-1][4]}
                )
        print_table(
            f"Recovery after a 5 s cut of the reasoner's host, {args.robots} robots (seconds "
            f"after the link is back; median of {args.runs} runs)",
            [
                "hosts' TCP",
                "changesets/s",
                "c caught up (s)",
                "reasoner caught up (s)",
                "every host agrees (s)",
                "worst (s)",
                "missed on c (changesets)",
            ],
            cuts,
        )
    else:
        print(f"recovery skipped: {reason}", flush=True)
    if args.json:
        for line in lines:
            print(
                json.dumps({k: round(v, 3) if isinstance(v, float) else v for k, v in line.items()})
            )
    path = png(args, "fleet.png")
    if path is not None and counts:
        print(f"plot: {plot({n: sizes[(trees[-1][0], n)] for n in counts}, load, cuts, path)}")


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=3, help="runs per measurement (default 3)")
    parser.add_argument("--samples", type=int, default=100, help="battery changes per run")
    parser.add_argument(
        "--sizes",
        type=int,
        nargs="*",
        default=list(SIZES),
        metavar="N",
        help="fleet sizes of the update latency (default 1 10 25 50; none: skip it)",
    )
    parser.add_argument("--seconds", type=float, default=60, help="sustained run length")
    parser.add_argument("--robots", type=int, default=200, help="robots in the sustained run")
    parser.add_argument("--hz", type=float, default=10, help="changes per robot per second")
    parser.add_argument(
        "--cut-hz",
        type=float,
        nargs="+",
        default=[1.0, 10.0],
        help="changes per robot per second during the recovery runs (default 1 10)",
    )
    parser.add_argument(
        "--old", type=Path, metavar="TREE", help="also run the store and reasoner from TREE"
    )
    parser.add_argument("--no-recovery", dest="recovery", action="store_false")
    main(parse(parser, own_json=True, own_plot=True))
