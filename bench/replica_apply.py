"""A cluster replica's apply of the log, in one process: CPU per changeset, and Oxigraph's floor.

Every replica installs every committed changeset into its space state and
commits it into its own Oxigraph store (`ClusterSpace.install_at`, then
`StoreDB.commit(..., revision=)`, as `cluster_writer.apply_pending` does).
This measures those two steps alone, without etcd, Zenoh or other processes,
on the changesets `cluster_bench.py --store` makes: 64 robots each rewriting
its own functional battery level, with a request id, `--batch` changesets a
commit. The thread's CPU time, per changeset, after a third of the commits
as warm-up.

Beside it, the floor under any layout: the same rewrites as bare SPARQL
UPDATEs with no tspace code, the value replaced (2 quads), then the value and
its timestamp (4 quads, what the store must keep to survive a restart).

With `--old TREE` the same runs with the code of TREE (its own process),
interleaved with this code's.

    .venv/bin/python bench/replica_apply.py [--runs 3] [--batch 4 17 64] [--old TREE]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import uuid
from pathlib import Path

from _harness import code_env, median
from _output import bench_parser, parse, print_table

ROBOTS, CHANGESETS = 64, 10_200
P = "<https://w3id.org/tspace/selfconfig#batteryLevel>"
INT = "http://www.w3.org/2001/XMLSchema#integer"


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_THREAD)
    return r.ru_utime + r.ru_stime


def _level(n: int) -> str:
    return f'"{n}"^^<{INT}>'


def apply(batch: int) -> dict[str, float]:
    """Install and commit functional rewrites as a replica does; us of CPU per changeset."""
    from space.changeset import WIRE_VERSION, pack
    from space.store.cluster_state import ClusterSpace
    from space.store.db import StoreDB

    rdf_type = "<http://www.w3.org/1999/02/22-rdf-syntax-ns#type>"
    functional = "<http://www.w3.org/2002/07/owl#FunctionalProperty>"
    with tempfile.TemporaryDirectory() as tmp:
        db = StoreDB(Path(tmp))
        state = ClusterSpace("bench", db)
        declared = {"v": WIRE_VERSION, "id": "decl", "agent": "b", "ts": "1/0", "seq": 1}
        declared["add"] = [[P, rdf_type, functional]]
        db.commit([state.install_at(pack(declared), 1).entry], revision=1)
        state.settle()
        seq, levels = 1, [0] * ROBOTS
        spent = {"install": 0.0, "commit": 0.0}
        counted = 0
        commits = CHANGESETS // batch
        for n in range(commits):
            began = _cpu()
            nets = []
            for _ in range(batch):
                robot = seq % ROBOTS
                seq += 1
                levels[robot] += 1
                s = f"<http://ex.org/robot{robot}>"
                wire = {"v": WIRE_VERSION, "id": uuid.uuid4().hex, "agent": "bench", "seq": seq}
                wire["ts"] = f"{7452 * 10**15 + seq}/79c651f11de1a2a3"
                wire["add"] = [[s, P, _level(levels[robot])]]
                if levels[robot] > 1:
                    wire["del"] = [[s, P, _level(levels[robot] - 1)]]
                nets.append(state.install_at(pack(wire), seq))
            installed = _cpu()
            db.commit([net.entry for net in nets], revision=n + 2)
            state.settle()
            if n >= commits // 3:
                spent["install"] += installed - began
                spent["commit"] += _cpu() - installed
                counted += batch
        db.close()
    return {k: v / counted * 1e6 for k, v in spent.items()}


def floor(batch: int, stamps: bool) -> float:
    """Commit the rewrites' minimal quads as SPARQL UPDATEs; us of CPU per changeset."""
    import pyoxigraph as ox

    t, st = "<urn:tspace:graph:bench:asserted>", "<urn:tspace:graph:bench:stamps>"
    with tempfile.TemporaryDirectory() as tmp:
        store = ox.Store(tmp)
        seq, levels, spent, counted = 0, [0] * ROBOTS, 0.0, 0
        commits = CHANGESETS // batch
        for n in range(commits):
            began = _cpu()
            gone, new = [], []
            for _ in range(batch):
                robot = seq % ROBOTS
                seq += 1
                levels[robot] += 1
                s = f"<http://ex.org/robot{robot}>"
                new.append(f"GRAPH {t} {{ {s} {P} {_level(levels[robot])} }}")
                if stamps:
                    new.append(f'GRAPH {st} {{ {s} {P} "{7452 * 10**15 + seq}/79c651f11d" }}')
                if levels[robot] > 1:
                    gone.append(f"GRAPH {t} {{ {s} {P} {_level(levels[robot] - 1)} }}")
                    if stamps:
                        old = f'"{7452 * 10**15 + seq - ROBOTS}/79c651f11d"'
                        gone.append(f"GRAPH {st} {{ {s} {P} {old} }}")
            ops = [f"DELETE DATA {{ {' '.join(gone)} }}"] if gone else []
            store.update(" ;\n".join([*ops, f"INSERT DATA {{ {' '.join(new)} }}"]))
            if n >= commits // 3:
                spent += _cpu() - began
                counted += batch
    return spent / counted * 1e6


def _child(batch: int) -> dict[str, float]:
    return json.loads(
        subprocess.run(
            [sys.executable, __file__, "--child", str(batch)],
            capture_output=True,
            text=True,
            check=True,
            env=code_env(_child.tree),  # type: ignore[attr-defined]
        ).stdout
    )


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--batch", type=int, nargs="+", default=[4, 17, 64])
    parser.add_argument("--old", type=Path, help="a source tree of the code before")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parse(parser)
    if args.child:
        print(json.dumps(apply(args.child)))
        return
    trees = {"old": args.old, "new": None} if args.old else {"new": None}
    results: dict[tuple[str, int], list[dict[str, float]]] = {}
    for _ in range(args.runs):
        for batch in args.batch:
            for name, tree in trees.items():
                _child.tree = tree  # type: ignore[attr-defined]
                results.setdefault((name, batch), []).append(_child(batch))
            for stamps in (False, True):
                results.setdefault((f"floor{int(stamps)}", batch), []).append(
                    {"commit": floor(batch, stamps)}
                )
    rows = []
    for batch in args.batch:
        row: list[object] = [batch]
        for name in trees:
            runs = results[(name, batch)]
            row += [median([r["install"] for r in runs]), median([r["commit"] for r in runs])]
        row += [median([r["commit"] for r in results[(f"floor{i}", batch)]]) for i in (0, 1)]
        rows.append(row)
    header = ["changesets a commit"]
    for name in trees:
        header += [f"{name}: install us/cs", f"{name}: commit us/cs"]
    header += ["Oxigraph alone: value replaced us/cs", "value and stamp replaced us/cs"]
    print_table(
        f"a replica's apply of functional rewrites, CPU us per changeset, medians of {args.runs}",
        header,
        rows,
    )


if __name__ == "__main__":
    main()
