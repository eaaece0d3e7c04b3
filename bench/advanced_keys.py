"""What an advanced publisher per part key would cost the store, against its plain puts.

Run: python bench/advanced_keys.py [--keys 2000]
The store publishes a changeset's parts with `session.put` on `@/changes/<s>/<p>`, one key
per subject and predicate (up to 200,000 remembered a space). Zenoh's sample cache and miss
detection come per `AdvancedPublisher`, one key each: this declares one per key (cache of 8,
sporadic heartbeat) and puts once on each, against one `session.put` per key, in one process
with its router; the figures are the time to declare, the time a put, and the process's RSS
growth.
"""

from __future__ import annotations

import time
from pathlib import Path

import zenoh
from _harness import free_port
from _output import bench_parser, parse, print_table
from zenoh import ext

from space.zconfig import make_config

PAYLOAD = b"x" * 300


def rss() -> int:
    """Return this process's resident set size in bytes."""
    return int(Path("/proc/self/statm").read_text().split()[1]) * 4096


def measure(session: zenoh.Session, n: int, advanced: bool) -> list[object]:
    """Return [declare ms, put us, RSS MB] for `n` keys, each published once."""
    keys = [f"tspace/bench/@/changes/<s{i}>/<p{advanced:d}>" for i in range(n)]
    before = rss()
    start = time.perf_counter()
    publishers = [
        ext.declare_advanced_publisher(
            session,
            key,
            cache=ext.CacheConfig(8),
            sample_miss_detection=ext.MissDetectionConfig(heartbeat=None, sporadic_heartbeat=0.5),
        )
        for key in keys
        if advanced
    ]
    declared = time.perf_counter()
    if advanced:
        for publisher in publishers:
            publisher.put(PAYLOAD)
    else:
        for key in keys:
            session.put(key, PAYLOAD)
    done = time.perf_counter()
    time.sleep(1)  # heartbeats and replies settle before RSS is read
    grown = rss() - before
    for publisher in publishers:
        publisher.undeclare()
    name = "AdvancedPublisher per key" if advanced else "session.put (the store now)"
    return [name, 1e3 * (declared - start), 1e6 * (done - declared) / n, grown / 1e6]


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--keys", type=int, default=2000)
    args = parse(parser)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        zenoh.open(make_config(mode="router", listen=[endpoint])),
        zenoh.open(make_config(mode="client", connect=[endpoint])) as session,
    ):
        rows = [measure(session, args.keys, advanced) for advanced in (False, True)]
    print_table(
        f"{args.keys} part keys, each published once",
        ["how", "declare ms", "put us", "RSS MB"],
        rows,
    )


if __name__ == "__main__":
    main()
