"""How long a subscriber takes to get back changes Zenoh lost on a link that stayed up.

Run: python bench/gap_recovery.py [--runs 3] [--count 200] [--old DIR]
The subscriber's router drops most whole-changeset samples (Zenoh's own `downsampling`
on its egress, `--freq` samples a second get through) while its links stay up: the loss
a congested route makes, with no reconnection nor store token coming back to say so.
The writer sends a changeset every 2 ms (`_latency_subscriber.py write ... nowait`), so
about 1 in 500/freq arrives live; each other one comes back when the next live one shows
the gap (from our log before, from the store's Zenoh cache with `zenoh.ext`'s advanced
publisher and subscriber), the last one on a heartbeat. Every figure is write ->
notification in ms, a median over runs of each run's: p50, p99, max, and `live` the
median of the changes that came through (each delivered once the gap before it was
filled: the repair's cost); and how many changes arrived of how many written. With
`--old`, each run measures that tree's store, writer and subscriber, then this tree's.
"""

from __future__ import annotations

import itertools
import json
import math
import statistics
import subprocess
import sys
from pathlib import Path

import zenoh
from _harness import code_env, free_port, percentile, serve_process
from _output import bench_parser, parse, print_table

from space import keys
from space.zconfig import make_config

BENCH = Path(__file__).parent


def lossy_router(store: str, space: str, freq: float) -> tuple[zenoh.Session, str]:
    """Open a router linked to `store` that forwards `freq` whole changesets a second."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conf = make_config(mode="router", listen=[endpoint], connect=[store])
    rule = {"key_expr": keys.service_key(space, "changes", keys.ROOT), "freq": freq}
    drop = {"messages": ["put"], "flows": ["egress"], "rules": [rule]}
    conf.insert_json5("downsampling", json.dumps([drop]))
    return zenoh.open(conf), endpoint


def run(code: Path | None, count: int, freq: float, space: str) -> list[float]:
    """Return each change's write -> notification delay (ms) through a lossy router."""
    child = [sys.executable, str(BENCH / "_latency_subscriber.py")]
    env = code_env(code)
    with serve_process(code) as (store, _pid):
        router, endpoint = lossy_router(store, space, freq)
        try:
            sub = subprocess.Popen(
                [*child, "subscribe", endpoint, space], stdout=subprocess.PIPE, text=True, env=env
            )
            assert sub.stdout is not None
            assert sub.stdout.readline().strip() == "ready"
            subprocess.run(
                [*child, "write", endpoint, space, str(count), "nowait"],
                check=True,
                env=env,
            )
            delays = [int(x) / 1e6 for x in sub.stdout.readline().split()]
            sub.wait(timeout=10)
        finally:
            router.close()
    return delays


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--count", type=int, default=200, help="changesets written per run")
    parser.add_argument("--freq", type=float, default=20.0, help="changesets/s the router passes")
    parser.add_argument("--old", type=Path, help="a source tree of the code before")
    args = parse(parser)
    trees: list[tuple[str, Path | None]] = [("new", None)]
    if args.old is not None:
        trees.insert(0, ("old", args.old.resolve()))
    figures: dict[str, list[tuple[float, ...]]] = {name: [] for name, _ in trees}
    for i in range(args.runs):
        for name, code in trees:
            d = run(code, args.count, args.freq, f"gap{i}{name}")
            through = live_delays(d)  # none when the router dropped nothing (a short run)
            live = statistics.median(through) if through else math.nan
            figures[name].append((live, percentile(d, 50), percentile(d, 99), max(d), len(d)))
            print(f"run {i} {name}: live {live:.2f} ms, p50 {figures[name][-1][1]:.2f} ms")
    rows = [
        [name, *(statistics.median(f[k] for f in runs) for k in range(4)),
         f"{min(f[4] for f in runs):.0f}/{args.count}"]
        for name, runs in figures.items()
    ]  # fmt: skip
    print_table(
        f"write -> notification through a router passing {args.freq:g} changesets/s "
        f"({args.count} written every 2 ms, {args.runs} runs)",
        ["tree", "live ms", "p50 ms", "p99 ms", "max ms", "delivered (fewest, cs)"],
        rows,
    )


def live_delays(delays: list[float]) -> list[float]:
    """Return the delays of the changes that came through: each is the last of its batch.

    A batch (the missed changes, then the one that showed the gap) is delivered at
    once, so its delays fall by 2 ms a change; the next batch starts at least 10 ms up.
    """
    return [d for d, after in itertools.pairwise(delays) if after > d + 10]


if __name__ == "__main__":
    main()
