"""A log compaction at `log_keep` entries: how long it holds the writer (a replica's worker).

Once a space's seq passed `log_keep` (100,000 by default), every `COMPACT_EVERY`
(1,000) commits of it the store deletes the entries older than the `log_keep`
latest, on the thread that commits: in a busy long-lived space, about once a
second at 1,000 changesets/s. This fills a store's log with `log_keep` +
1,000 entries (functional rewrites' payloads, request ids), then times its
first compaction and two after it, each 1,000 entries later; the thread's CPU
time and the wall clock, in ms.

With `--old TREE` the same runs with the code of TREE (its own process),
interleaved with this code's.

    .venv/bin/python bench/log_compaction.py [--runs 3] [--keep 100000] [--old TREE] [--json]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _harness import code_env, median
from _output import bench_parser, parse, print_table


def compactions(keep: int) -> dict[str, float]:
    """Return the ms (CPU, wall) of the first compaction and the median of the next two."""
    from space.store.db import COMPACT_EVERY, StoreDB
    from space.store.db_layout import log_quads

    payload = b"\x87\xa1v\x01\xa2id\xd9 " + b"7" * 260  # a rewrite's size, ~300 bytes
    with tempfile.TemporaryDirectory() as tmp:
        db = StoreDB(Path(tmp), log_keep=keep)
        seq, spent = 0, []
        for more in (keep + COMPACT_EVERY, COMPACT_EVERY, COMPACT_EVERY):
            quads = []
            for _ in range(more):
                seq += 1
                quads += log_quads("s", seq, f"{seq:032x}", payload)
            db.store.bulk_extend(quads)
            cpu, wall = time.thread_time(), time.perf_counter()
            db._compact("s", seq)
            spent.append((time.thread_time() - cpu, time.perf_counter() - wall))
        db.close()
    return {
        "first cpu": spent[0][0] * 1e3,
        "first wall": spent[0][1] * 1e3,
        "next cpu": median([s[0] for s in spent[1:]]) * 1e3,
        "next wall": median([s[1] for s in spent[1:]]) * 1e3,
    }


def _child(tree: Path | None, keep: int) -> dict[str, float]:
    done = subprocess.run(
        [sys.executable, __file__, "--child", "--keep", str(keep)],
        capture_output=True,
        text=True,
        check=True,
        env=code_env(tree),
    )
    return json.loads(done.stdout)


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--keep", type=int, default=100_000)
    parser.add_argument("--old", type=Path, help="a source tree of the code before")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parse(parser)
    if args.child:
        print(json.dumps(compactions(args.keep)))
        return
    trees = {"old": args.old, "new": None} if args.old else {"new": None}
    results: dict[str, list[dict[str, float]]] = {}
    for _ in range(args.runs):
        for name, tree in trees.items():
            results.setdefault(name, []).append(_child(tree, args.keep))
    keys = ("first cpu", "first wall", "next cpu", "next wall")
    rows = [[name, *(median([r[k] for r in results[name]]) for k in keys)] for name in trees]
    print_table(
        f"a compaction of the log at {args.keep} entries, ms, medians of {args.runs}",
        ["code", *(f"{k} ms" for k in keys)],
        rows,
    )


if __name__ == "__main__":
    main()
