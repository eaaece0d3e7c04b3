"""OWL 2 RL from scratch and per update: this engine against `reasonable` (and owlrl), one run.

For each size, a LUBM-like data set (bench/lubm.py) is loaded and
materialised by each system in a fresh process (so peak memory is its own):
  ours          RuleEngine.load_files: Oxigraph's parser into ids, set-at-a-time closure
  ours-rdflib   rdflib's parser (read_graph) + RuleEngine.load (--systems; slow to parse)
  main          --old DIR: the code of another checkout (its own bench's `ours`)
  reasonable    reasonable 0.4.4 (Rust): load_file + reason()
  owlrl         owlrl's DeductiveClosure on an rdflib Graph (--owlrl; up to 20k triples)
then ours times single-triple deletes and adds (each a data triple taken out
and put back, p50), and reasonable the same through update_graph + reason().
Runs alternate between systems so machine noise falls on all alike; the
table gives medians over --repeat runs. Writes a Markdown table (with --json, a JSON object
per line per case too) and a PNG (bench/out/owl_rl.png, or --plot PATH).

    python bench/owl_rl.py --departments 43 --repeat 3 --plot /tmp/owl_rl.png
    python bench/owl_rl.py --departments 43 425 --repeat 1 --old /path/to/main
"""

from __future__ import annotations

import argparse
import json
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _output import bench_parser, json_rows, parse, png

from bench.lubm import write

SYSTEMS = ("ours", "ours-rdflib", "reasonable")
DEFAULT = ("ours", "reasonable")
OWLRL_MAX = 20_000  # owlrl takes half a minute at 5k triples, and grows faster than linearly


def child(system: str, folder: Path, updates: int) -> dict:
    """Load and materialise in this process; return the times, triples and peak memory."""
    ontology, data, ttl = folder / "ontology.ttl", folder / "data.nt", folder / "data.ttl"
    _import(system)  # not timed: a long-running process imports once
    cpu0 = _cpu()
    start = time.perf_counter()
    result: dict = {}
    if system == "reasonable":
        import reasonable

        r = reasonable.PyReasoner()
        r.load_file(str(ontology))
        r.load_file(str(ttl))
        result["triples"] = len(r.reason())
        result["load_s"] = time.perf_counter() - start
        result["cpu_s"] = _cpu() - cpu0  # every thread's: fair on a loaded machine
        result["peak_mb"] = _peak_mb()
        if updates:
            result.update(_reasonable_updates(r, updates))
    elif system == "owlrl":
        import owlrl
        from rdflib import Graph

        g = Graph()
        g.parse(ontology)
        g.parse(data, format="nt")
        owlrl.DeductiveClosure(owlrl.OWLRL_Semantics).expand(g)
        result["triples"] = len(g)
        result["load_s"] = time.perf_counter() - start
        result["cpu_s"] = _cpu() - cpu0  # every thread's: fair on a loaded machine
    else:
        from space.reasoning import RuleEngine, read_graph

        warnings.simplefilter("ignore")
        engine = RuleEngine([], read_graph([ontology]))
        if system == "ours":
            engine.load_files([data])
        else:
            engine.load(read_graph([data]))
        result["triples"] = engine.count()
        result["load_s"] = time.perf_counter() - start
        result["cpu_s"] = _cpu() - cpu0  # every thread's: fair on a loaded machine
        result["peak_mb"] = _peak_mb()
        if updates and system == "ours":
            from space.reasoning import read_triples

            result.update(_our_updates(engine, read_triples([data]), updates))
    result.setdefault("peak_mb", _peak_mb())
    return result


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _import(system: str) -> None:
    if system == "reasonable":
        import reasonable  # noqa: F401
    elif system == "owlrl":
        import owlrl  # noqa: F401
    else:
        import space.reasoning  # noqa: F401


def _our_updates(engine, triples: list, n: int) -> dict:
    rnd = random.Random(1)
    deletes, adds = [], []
    for triple in rnd.sample(triples, n):
        t0 = time.perf_counter()
        engine.apply(removed=[triple])
        t1 = time.perf_counter()
        engine.apply(added=[triple])
        t2 = time.perf_counter()
        deletes.append(t1 - t0)
        adds.append(t2 - t1)
    return {"delete_p50_ms": _p50(deletes), "add_p50_ms": _p50(adds)}


def _reasonable_updates(r, n: int) -> dict:
    from rdflib import Graph

    base = Graph()
    for triple in r.get_base_triples():
        base.add(triple)
    rnd = random.Random(1)
    deletes, adds = [], []
    for triple in rnd.sample(sorted(base), n):
        base.remove(triple)
        t0 = time.perf_counter()
        r.update_graph(base)
        r.reason()
        t1 = time.perf_counter()
        base.add(triple)
        r.update_graph(base)
        r.reason()
        t2 = time.perf_counter()
        deletes.append(t1 - t0)
        adds.append(t2 - t1)
    return {"delete_p50_ms": _p50(deletes), "add_p50_ms": _p50(adds)}


def _p50(values: list[float]) -> float:
    return statistics.median(values) * 1000


def run(system: str, folder: Path, updates: int, old: Path | None = None) -> dict:
    """Run one system in a fresh process; return its result (`main`: the bench of `old`)."""
    script = old / "bench" / "owl_rl.py" if system == "main" and old else Path(__file__)
    out = subprocess.run(
        [
            sys.executable,
            str(script),
            "--child",
            "ours" if system == "main" else system,
            "--dir",
            str(folder),
            "--updates",
            str(updates),
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--departments", type=int, nargs="+", default=[43])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--updates", type=int, default=20, help="single-triple updates timed")
    parser.add_argument("--reasonable-updates", type=int, default=3)
    parser.add_argument("--owlrl", action="store_true", help="add owlrl (slow: small sizes)")
    parser.add_argument(
        "--systems", nargs="+", choices=SYSTEMS, default=list(DEFAULT), help="default: %(default)s"
    )
    parser.add_argument("--old", type=Path, help="a checkout whose code runs beside, as `main`")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--dir", type=Path, help=argparse.SUPPRESS)
    args = parse(parser, own_plot=True)
    if args.child:
        print(json.dumps(child(args.child, args.dir, args.updates)))
        return
    systems = [*args.systems, "owlrl"] if args.owlrl else list(args.systems)
    if args.old:
        systems.insert(1, "main")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for departments in args.departments:
            folder = Path(tmp) / f"d{departments}"
            _, data = write(departments, folder)
            (folder / "data.ttl").write_bytes(data.read_bytes())  # reasonable reads ttl/n3 only
            size = sum(1 for _ in data.open())
            here = [s for s in systems if s != "owlrl" or size <= OWLRL_MAX]
            results: dict[str, list[dict]] = {s: [] for s in here}
            for i in range(args.repeat):
                for system in here:
                    updates = 0
                    if i == 0 and system in ("ours", "main"):
                        updates = args.updates
                    elif i == 0 and system == "reasonable":
                        updates = args.reasonable_updates
                    results[system].append(run(system, folder, updates, args.old))
                    print(f"{size} {system} run {i}: {results[system][-1]}", file=sys.stderr)
            rows.append((size, results))
    header, cells = _cells(rows)
    print(_markdown(header, cells))
    if args.json:
        print("\n".join(json_rows("OWL 2 RL, medians", header, cells)))
    path = png(args, "owl_rl.png")
    if path is not None:
        _plot([(size, {s: r for s, r in res.items() if s != "owlrl"}) for size, res in rows], path)
        print(f"\nwrote {path}")


def _median(runs: list[dict], key: str) -> float | None:
    values = [r[key] for r in runs if key in r]
    return statistics.median(values) if values else None


def _cells(rows: list) -> tuple[list[str], list[list[object]]]:
    """Return the table's header and rows: medians per system and size, None where not run."""
    header = ["case", "data triples", "closure triples", "load+materialise s", "CPU s"]
    header += ["peak MB", "CPU vs reasonable x", "peak vs reasonable x"]
    header += ["delete p50 ms", "add p50 ms"]
    cells = []
    for size, results in rows:
        peer = results.get("reasonable")
        for system, runs in results.items():
            row = [system, size, runs[0]["triples"]]
            row += [_median(runs, k) for k in ("load_s", "cpu_s", "peak_mb")]
            if peer and system != "reasonable":
                row += [_median(runs, k) / _median(peer, k) for k in ("cpu_s", "peak_mb")]
            else:
                row += [None, None]
            row += [_median(runs, k) for k in ("delete_p50_ms", "add_p50_ms")]
            cells.append(row)
    return header, cells


def _markdown(header: list[str], cells: list[list[object]]) -> str:
    def shown(c: object) -> str:
        if c is None:
            return "-"
        return f"{c:,}" if isinstance(c, int) else f"{c:,.2f}"

    lines = ["| " + " | ".join(header) + " |", "|---|" + "---:|" * (len(header) - 1)]
    for row in cells:
        lines.append("| " + " | ".join([str(row[0]), *map(shown, row[1:])]) + " |")
    return "\n".join(lines)


def _plot(rows: list, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key, label in (
        (axes[0], "cpu_s", "load + materialise (CPU s)"),
        (axes[1], "peak_mb", "peak memory (MB)"),
    ):
        width = 0.8 / len(rows[0][1])
        for j, system in enumerate(rows[0][1]):
            xs = [i + j * width for i in range(len(rows))]
            ys = [_median(results[system], key) or 0 for _, results in rows]
            ax.bar(xs, ys, width, label=system)
        ax.set_xticks([i + 0.4 - width / 2 for i in range(len(rows))])
        ax.set_xticklabels([f"{size:,} triples" for size, _ in rows])
        ax.set_ylabel(label)
    axes[0].legend()
    fig.suptitle("OWL 2 RL on a LUBM-like data set (medians)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    main()
