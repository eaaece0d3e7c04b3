"""The reasoner's path for one change, in process: payload in, engine, answer payload out.

Issue 13, point 2: terms carried in their wire form. The reasoner agent reads each
published changeset, applies it to its engine and encodes its answer. This bench times
that path both ways on two engines built alike, run by run in turn, CPU clock:

- `rdflib terms` (the reasoner before): `Changeset.decode` parses every term into an
  rdflib term, `Engine.apply` encodes them into ids, the `Delta` is decoded back into
  rdflib terms and the answer turns them into N-Triples again;
- `texts`: `Changeset.decode(texts=True)` leaves the N-Triples texts, the engine's term
  table gives them in its form of each term (`canonical`, as the reasoner does before
  noting who wrote them), `apply_texts` goes from text to id with one dict lookup a term
  and gives the `Delta` in texts, which the answer packs as they are.

Cases: the battery goes "very low" and the paper-shaped rules all fire (a few triples in,
an answer of 2n); then the change that undoes it (2n + 2 triples in, no firing), as the
end-to-end bench's reset is. The parse caches of `space.terms` are warm for the rdflib
path (the same 2n terms recur), its best case.

    python bench/reasoner_path.py --runs 30 --sizes 200 1000
"""

from __future__ import annotations

import statistics
import time

from _output import bench_parser, parse, print_table
from rdflib import Literal
from rules_scaling import AC, BATTERY_LOW, BATTERY_NORMAL, as_the_reasoner_runs, prepared_engine

from space import Changeset
from space.reasoning import Engine

PATHS = ("rdflib terms", "texts")


def payload(added: list, removed: list, seq: int) -> bytes:
    """Return a changeset as the store publishes it."""
    return Changeset(agent="hw", timestamp="1/ab", added=added, removed=removed, seq=seq).encode()


def answer(engine: Engine, data: bytes, texts: bool) -> bytes:
    """Decode a published change, apply it, and encode the answer: the reasoner's path."""
    cs = Changeset.decode(data, published=True, texts=texts)
    if texts:  # in the engine's form of each term first, as the reasoner takes them
        canonical = engine.terms.canonical
        delta = engine.apply_texts(canonical(cs.added), canonical(cs.removed))  # type: ignore[arg-type]
    else:
        delta = engine.apply(added=cs.added, removed=cs.removed)
    out = Changeset(
        agent="reasoner",
        timestamp="2/ab",
        cause=cs.id,
        added=list(delta.asserted_added),
        removed=list(delta.asserted_removed),
        inferred_added=list(delta.inferred_added),
        inferred_removed=list(delta.inferred_removed),
        texts=texts,
    )
    return out.encode()


def measure(n: int, runs: int) -> dict[tuple[str, str], list[float]]:
    """Return CPU seconds per case and path over `runs` runs of each, in turn."""
    lows = [(AC.robot1_base, AC[f"setting_{i}"], Literal("low")) for i in range(n)]
    normals = [(AC.robot1_base, AC[f"setting_{i}"], Literal("normal")) for i in range(n)]
    fire = payload([BATTERY_LOW], [BATTERY_NORMAL], 1)
    undo = payload([BATTERY_NORMAL, *normals], [BATTERY_LOW, *lows], 2)
    engines = {path: prepared_engine(n) for path in PATHS}
    sizes: dict[str, int] = {}
    samples: dict[tuple[str, str], list[float]] = {}
    with as_the_reasoner_runs():
        for _ in range(runs):
            for path, engine in engines.items():
                for case, data in (("fire", fire), ("undo", undo)):
                    start = time.process_time()
                    out = answer(engine, data, path == "texts")
                    samples.setdefault((case, path), []).append(time.process_time() - start)
                    sizes[f"{case} {path}"] = len(out)
    fired = Changeset.decode(answer(engines["texts"], fire, True))
    if len(fired.added) != n:
        raise SystemExit(f"{n} rules: the answer adds {len(fired.added)} triples, not {n}")
    answer(engines["texts"], undo, True)
    if sizes["fire texts"] != sizes["fire rdflib terms"]:
        raise SystemExit("the two paths' answers differ in size")
    return samples


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=30, help="runs per case and path")
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1000], help="rules")
    options = parse(parser)
    rows = []
    for n in options.sizes:
        samples = measure(n, options.runs)
        for case, label in (("fire", f"{n} rules fire"), ("undo", f"undone, {2 * n + 2} in")):
            old, new = (statistics.median(samples[case, path]) * 1000 for path in PATHS)
            rows.append([label, old, new, new / old])
    print_table(
        "decode + engine + answer encoded, CPU ms p50 per change "
        f"({options.runs} runs each, in turn)",
        ["case", "rdflib terms (ms)", "texts (ms)", "texts / rdflib"],
        rows,
    )


if __name__ == "__main__":
    main()
