"""Differential test: random rule sets and update sequences, through tspace, Jena 4.5 and a
naive closure, every difference classified.

    python bench/jena_diff.py [--seed 1] [--sets 60] [--steps 6]

Needs Java and Jena 4.5's jars (see bench/jena_referee.py). Two families:

- monotone (joins, constants, arithmetic, comparisons) under adds and removes: tspace,
  Jena (forwardRETE, incremental) and a naive oracle (the closure of the asserted
  triples, recomputed from scratch with its own evaluator) after every step;
- production (noValue, drop, remove) on loaded data: tspace and Jena.

Classes: `agree`; `jena-deletion` (Jena misses triples the oracle and tspace still derive,
after a remove: Jena keeps no derivation counts); `production-order` (a production set
whose firings Jena orders otherwise); `other` (unexplained: a bug somewhere).
"""

from __future__ import annotations

import logging
import random
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

from rdflib import XSD, Literal, URIRef
from rdflib.term import Node

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _output import bench_parser, parse, print_table
from jena_referee import ROOT, classpath

from space.reasoning import RuleEngine, default_registry, parse_rules
from space.terms import to_nt

EG = "urn:x-hp:eg/"
P = [f"p{i}" for i in range(4)]
C = [f"a{i}" for i in range(5)]
Triple = tuple[Node, Node, Node]


def rule_set(rng: random.Random, production: bool) -> tuple[str, list[tuple]]:
    """Return Jena rule text and its rules as data for the naive oracle."""
    texts, model = [], []
    for i in range(rng.randint(2, 5)):
        kind = rng.choice(
            ["copy", "join", "const", "sum", "less"] + (["noValue"] * 3 if production else [])
        )
        p, q, r = rng.sample(P, 3)
        if kind == "copy":
            texts.append(f"[c{i}: (?x eg:{p} ?y) notLiteral(?y) -> (?y eg:{q} ?x)]")
        elif kind == "join":
            texts.append(f"[j{i}: (?x eg:{p} ?y) (?y eg:{q} ?z) -> (?x eg:{r} ?z)]")
        elif kind == "const":
            c = rng.choice(C)
            texts.append(f"[k{i}: (?x eg:{p} eg:{c}) -> (?x eg:{q} eg:{c})]")
        elif kind == "sum":
            texts.append(
                f"[s{i}: (?x eg:{p} ?n) isLiteral(?n) sum(?n, 1, ?m) lessThan(?m, 4)"
                f" -> (?x eg:{p} ?m)]"
            )
        elif kind == "less":
            texts.append(
                f"[l{i}: (?x eg:{p} ?n) (?y eg:{q} ?m) lessThan(?n, ?m) -> (?x eg:{r} ?y)]"
            )
        else:
            texts.append(f"[n{i}: (?x eg:{p} ?y) noValue(?y eg:{q}) -> (?y eg:{q} eg:none)]")
        model.append((kind, p, q, r, texts[-1]))
    return "\n".join(texts) + "\n", model


def random_triple(rng: random.Random) -> Triple:
    s = URIRef(EG + rng.choice(C))
    p = URIRef(EG + rng.choice(P))
    if rng.random() < 0.3:
        o: Node = Literal(str(rng.randint(0, 3)), datatype=XSD.int)
    else:
        o = URIRef(EG + rng.choice(C))
    return (s, p, o)


def naive(model: list[tuple], asserted: set[Triple]) -> set[Triple]:
    """Close the asserted triples under monotone rules by brute force (an independent oracle)."""
    state = set(asserted)
    eg = lambda name: URIRef(EG + name)  # noqa: E731
    while True:
        new = set()
        by_p: dict[Node, list[Triple]] = {}
        for t in state:
            by_p.setdefault(t[1], []).append(t)
        for kind, p, q, r, text in model:
            if kind == "copy":
                new |= {
                    (y, eg(q), x) for x, _, y in by_p.get(eg(p), []) if not isinstance(y, Literal)
                }
            elif kind == "join":
                for x, _, y in by_p.get(eg(p), []):
                    new |= {(x, eg(r), z) for y2, _, z in by_p.get(eg(q), []) if y2 == y}
            elif kind == "const":
                c = text.split("eg:")[2].split(")")[0]
                new |= {(x, eg(q), eg(c)) for x, _, o in by_p.get(eg(p), []) if o == eg(c)}
            elif kind == "sum":
                for x, _, n in by_p.get(eg(p), []):
                    if isinstance(n, Literal) and isinstance(n.value, int) and n.value + 1 < 4:
                        new.add((x, eg(p), Literal(str(n.value + 1), datatype=XSD.int)))
            elif kind == "less":
                for x, _, n in by_p.get(eg(p), []):
                    for y, _, m in by_p.get(eg(q), []):
                        if _num(n) is not None and _num(m) is not None and _num(n) < _num(m):
                            new.add((x, eg(r), y))
        if new <= state:
            return state
        state |= new


def _num(term: Node) -> float | None:
    value = term.value if isinstance(term, Literal) else None
    return value if isinstance(value, int | float) and not isinstance(value, bool) else None


def ours(rules: str, steps: list[tuple[str, Triple]]) -> list[set[Triple]]:
    engine = RuleEngine(parse_rules(rules, default_registry(), warn=lambda m: None), owl=False)
    engine.load()
    states = []
    for op, triple in steps:
        if op == "=":
            states.append(set(engine.graph))
        elif op == "+":
            engine.apply(added=[triple])
        else:
            engine.apply(removed=[triple])
    return states


def main(seed: int, sets: int, steps: int) -> None:
    logging.disable(logging.WARNING)
    rng = random.Random(seed)
    cases = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        jobs = []
        for n in range(sets):
            production = n % 3 == 2
            rules, model = rule_set(rng, production)
            rules = f"@prefix eg: <{EG}>.\n" + rules
            sequence: list[tuple[str, Triple]] = []
            present: list[Triple] = []
            for _ in range(rng.randint(3, 8)):
                t = random_triple(rng)
                sequence.append(("+", t))
                present.append(t)
            sequence.append(("=", None))  # type: ignore[arg-type]
            for _ in range(0 if production else steps):
                if present and rng.random() < 0.5:
                    t = present.pop(rng.randrange(len(present)))
                    sequence.append(("-", t))
                else:
                    t = random_triple(rng)
                    present.append(t)
                    sequence.append(("+", t))
                sequence.append(("=", None))  # type: ignore[arg-type]
            (work / f"{n}.rules").write_text(rules)
            (work / f"{n}.steps").write_text(
                "".join(
                    "=\n" if op == "=" else f"{op} {' '.join(to_nt(x) for x in t)} .\n"
                    for op, t in sequence
                )
            )
            jobs.append(
                [
                    "steps",
                    "forwardRETE",
                    str(work / f"{n}.rules"),
                    str(work / f"{n}.out"),
                    str(work / f"{n}.steps"),
                ]
            )
            cases.append((n, production, rules, model, sequence))
        cp = classpath(work)
        classes = work / "classes"
        source = ROOT / "bench" / "jena_referee" / "Referee.java"
        subprocess.run(
            ["javac", "-nowarn", "-cp", cp, "-d", str(classes), str(source)],
            check=True,
            capture_output=True,
        )
        (work / "jobs.tsv").write_text("".join("\t".join(j) + "\n" for j in jobs))
        subprocess.run(
            ["java", "-cp", f"{classes}:{cp}", "Referee", str(work / "jobs.tsv")], check=False
        )
        tally: Counter[str] = Counter()
        examples: dict[str, str] = {}
        for n, production, rules, model, sequence in cases:
            jena_states = _jena_states((work / f"{n}.out").read_text())
            our_states = ours(rules, sequence)
            asserted: set[Triple] = set()
            oracle_states = []
            for op, t in sequence:
                if op == "=":
                    oracle_states.append(naive(model, asserted) if not production else None)
                elif op == "+":
                    asserted.add(t)
                else:
                    asserted.discard(t)
            removed_before = False
            for i, (mine, jena, oracle) in enumerate(
                zip(our_states, jena_states, oracle_states, strict=False)
            ):
                removed_before = removed_before or any(
                    op == "-" for op, _ in sequence[: _index(sequence, i)]
                )
                if jena is None:
                    label = "jena-error"
                elif _same(mine, jena) and (oracle is None or _same(mine, oracle)):
                    label = "agree"
                elif (
                    oracle is not None
                    and _same(mine, oracle)
                    and removed_before
                    and _subset(jena, mine)
                ):
                    label = "jena-deletion"
                elif production:
                    label = "production-order"
                else:
                    label = "other"
                tally[label] += 1
                examples.setdefault(label, f"set {n} state {i}:\n{rules}")
    total = sum(tally.values())
    print_table(
        f"{sets} rule sets, {total} states compared (seed {seed})",
        ["class", "states (count)"],
        tally.most_common(),
    )
    for label, example in examples.items():
        if label not in ("agree",):
            print(f"\nexample of {label}: {example}")


def _index(sequence: list, state: int) -> int:
    seen = -1
    for i, (op, _) in enumerate(sequence):
        if op == "=":
            seen += 1
            if seen == state:
                return i
    return len(sequence)


def _jena_states(text: str) -> list[set[Triple] | None]:
    if text.startswith(("error", "timeout")):
        return [None] * 100
    from rdflib import Graph

    states: list[set[Triple] | None] = []
    for chunk in text.split("# state ")[1:]:
        body = chunk.split("\n", 1)[1] if "\n" in chunk else ""
        states.append(set(Graph().parse(data=body, format="nt")))
    return states


def _same(a: set[Triple], b: set[Triple]) -> bool:
    return {_key(t) for t in a} == {_key(t) for t in b}


def _subset(a: set[Triple], b: set[Triple]) -> bool:
    return {_key(t) for t in a} <= {_key(t) for t in b}


def _key(t: Triple) -> tuple:
    return tuple(x.value if isinstance(x, Literal) and _num(x) is not None else x for x in t)


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--sets", type=int, default=60)
    parser.add_argument("--steps", type=int, default=6)
    args = parse(parser)
    main(args.seed, args.sets, args.steps)
