"""Does a store slow down as robots keep rewriting their functional readings?

Each decision on a functional property reads the value it replaces. Every
rewrite leaves RocksDB a tombstone under that (subject, property) until a
compaction reaches it, so a scan of the pair slows down with every reading
written before (space/store/values.py). Here 64 robots keep rewriting their
own battery level through one embedded store (`tspace serve`, the client of
`cluster_bench.py --store`) for several phases in a row; each phase reports
acknowledged changesets/s and the store's CPU per changeset. With `--old
TREE`, a store of the code in TREE does the same in the same run, the two
stores' phases taken in turns.

    .venv/bin/python bench/functional_rewrites.py [--phases 6] [--seconds 10] [--old TREE]
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from _cluster_store import throughput
from _harness import serve_process
from _output import bench_parser, parse, print_table


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--phases", type=int, default=6)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--inflight", type=int, default=64)
    parser.add_argument("--old", type=Path, help="a source tree of the code before")
    args = parse(parser)
    codes = {"now": None} if args.old is None else {"now": None, "before": args.old}
    rows, written = [], dict.fromkeys(codes, 0.0)
    with contextlib.ExitStack() as stack:
        stores = {name: stack.enter_context(serve_process(code)) for name, code in codes.items()}
        for i in range(args.phases):
            row: list = [i + 1]
            for name, (endpoint, pid) in stores.items():
                r = throughput([endpoint], args.seconds, args.inflight, {"store": [pid]})
                written[name] += r["rate"] * args.seconds
                row += [round(written[name] / args.inflight), r["rate"], r["p99"], r["cpu store"]]
            rows.append([*row, os.getloadavg()[0]])
            print(rows[-1], flush=True)
    header = ["phase"]
    for name in codes:
        header += [f"{name}: readings per robot", f"{name}: cs/s", f"{name}: p99 ms"]
        header.append(f"{name}: cpu ms/cs")
    print_table(
        f"64 robots rewriting their battery level through one store, {args.seconds:g} s phases",
        [*header, "load (1 min)"],
        rows,
    )


if __name__ == "__main__":
    main()
