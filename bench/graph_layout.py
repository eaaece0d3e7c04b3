"""What a commit costs Oxigraph by where its triples live: a named graph or the default graph.

The store keeps each space's asserted triples in a named graph (`db_layout`), and Oxigraph
indexes a named graph's quad six ways (gspo, gpos, gosp, spog, posg, ospg), the default
graph's three (spo, pos, osp). This times the reasoner's firing answer as the store commits
it, N settings flipped (N removed, N added) in one SPARQL update, on an Oxigraph store on disk
holding `--background` other triples, in either place (in turns, `--rounds` times each, a
fresh store each time); and the same through `Store.remove` and `Store.extend` (no SPARQL
text to parse), to tell parsing from storing. Medians of all the flips, milliseconds.
(`bench/floors.py` times more ways of writing, into a named graph only; its default-graph
row is a load into a graph that holds nothing else, where here both places hold the same.)

    python bench/graph_layout.py [--settings 200] [--runs 40] [--rounds 3] [--background 20000]
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections.abc import Callable

import pyoxigraph as ox
from _output import bench_parser, parse, print_table

NAMED = ox.NamedNode("urn:tspace:graph:bench:asserted")
S = ox.NamedNode("https://w3id.org/tspace/selfconfig#robot1_base")
P = "https://w3id.org/tspace/selfconfig#setting_"


def _data(graph: ox.NamedNode | ox.DefaultGraph, n: int, value: str) -> str:
    triples = " . ".join(f'{S} <{P}{i}> "{value}"' for i in range(n))
    return f"GRAPH {graph} {{ {triples} }}" if isinstance(graph, ox.NamedNode) else triples


def _flip(graph: ox.NamedNode | ox.DefaultGraph, n: int, old: str, new: str) -> str:
    return f"DELETE DATA {{ {_data(graph, n, old)} }} ;\nINSERT DATA {{ {_data(graph, n, new)} }}"


def _quads(graph: ox.NamedNode | ox.DefaultGraph, n: int, value: str) -> list[ox.Quad]:
    return [ox.Quad(S, ox.NamedNode(f"{P}{i}"), ox.Literal(value), graph) for i in range(n)]


def measure(
    graph: ox.NamedNode | ox.DefaultGraph, n: int, runs: int, background: int
) -> dict[str, list[float]]:
    """Return the seconds of 2 * `runs` flips of n settings, by SPARQL update and by quads."""
    with tempfile.TemporaryDirectory(prefix="tspace-graphs-") as work:
        store = ox.Store(work)
        store.bulk_extend(
            ox.Quad(
                ox.NamedNode(f"urn:x:{i}"), ox.NamedNode(f"urn:p:{i % 50}"), ox.Literal(i), graph
            )
            for i in range(background)
        )
        store.extend(_quads(graph, n, "normal"))
        store.flush()
        timings = _flips(store, graph, n, runs)
        del store  # closed before its directory goes
    return timings


def _flips(
    store: ox.Store, graph: ox.NamedNode | ox.DefaultGraph, n: int, runs: int
) -> dict[str, list[float]]:
    texts = {v: _flip(graph, n, *v) for v in (("normal", "low"), ("low", "normal"))}
    quads = {v: _quads(graph, n, v) for v in ("normal", "low")}

    def by_quads(old: str, new: str) -> None:
        for q in quads[old]:
            store.remove(q)
        store.extend(quads[new])

    timings: dict[str, list[float]] = {"update": [], "quads": []}
    steps: dict[str, Callable[[str, str], None]] = {
        "update": lambda old, new: store.update(texts[(old, new)]),
        "quads": by_quads,
    }
    for _ in range(runs):
        for name, step in steps.items():
            for old, new in (("normal", "low"), ("low", "normal")):
                start = time.perf_counter()
                step(old, new)
                timings[name].append(time.perf_counter() - start)
    return timings


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--settings", type=int, default=200, help="settings flipped per commit")
    parser.add_argument("--runs", type=int, default=40, help="pairs of flips per round")
    parser.add_argument("--rounds", type=int, default=3, help="fresh stores per place")
    parser.add_argument("--background", type=int, default=20_000, help="other triples held")
    args = parse(parser)
    places = {"named graph": NAMED, "default graph": ox.DefaultGraph()}
    samples: dict[str, dict[str, list[float]]] = {p: {"update": [], "quads": []} for p in places}
    for _ in range(args.rounds):
        for name, graph in places.items():
            for how, t in measure(graph, args.settings, args.runs, args.background).items():
                samples[name][how] += t
    ms = {
        p: {how: statistics.median(t) * 1e3 for how, t in hows.items()}
        for p, hows in samples.items()
    }
    rows = [
        [p, m["update"], m["quads"], m["update"] / ms["named graph"]["update"]]
        for p, m in ms.items()
    ]
    print_table(
        f"{args.settings} settings flipped in one commit ({2 * args.settings} quads changed), "
        f"{args.background} other triples held; median of {2 * args.runs * args.rounds} commits",
        ["triples in", "SPARQL update (ms)", "remove + extend (ms)", "update / named (x)"],
        rows,
    )


if __name__ == "__main__":
    main()
