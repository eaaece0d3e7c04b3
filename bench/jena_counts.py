"""Count how much of Jena's own rule material a tspace checkout parses and answers as Jena.

    python bench/jena_counts.py [SPACE_ROOT] [--json] [--no-plot]

SPACE_ROOT (default: this checkout) is the folder holding the `space` package, so an
older commit (`git archive <commit> | tar -x -C /tmp/before`) can be measured with
today's recorded answers in tests/data/jena (written by bench/jena_referee.py).
"""

from __future__ import annotations

import inspect
import json
import logging
import re
import sys
from pathlib import Path
from typing import Any

from _output import bench_parser, parse, print_table

HERE = Path(__file__).resolve().parents[1]
JENA = HERE / "tests" / "data" / "jena"
DATA = {
    "rdfs-tbox1-data1": ("rdfs-tbox1.rdf", "rdfs-data1.rdf"),
    "rdfs-tbox1-data3": ("rdfs-tbox1.rdf", "rdfs-data3.rdf"),
    "owl-tbox-consistent": ("owl-tbox.owl", "owl-consistentData.rdf"),
}
_LINE = re.compile(r"^(<[^>]*>|_:\S+)\s+(<[^>]*>)\s+(.*\S)\s*\.$")


def main(root: Path) -> None:
    sys.path.insert(0, str(root))
    logging.disable(logging.CRITICAL)
    from rdflib import Graph
    from rdflib.compare import isomorphic
    from rdflib.util import from_n3, guess_format

    from space.reasoning import RuleEngine, default_registry, load_rules, parse_rules

    registry = default_registry()
    quiet = {"warn": lambda m: None} if "warn" in inspect.signature(load_rules).parameters else {}

    def parses(text: str) -> bool:
        try:
            parse_rules(text, registry, **quiet)
        except Exception:  # an old checkout may fail any way: not parsed
            return False
        return True

    def engine(rules: Path) -> Any:
        loaded = load_rules([rules], registry, **quiet)
        try:  # the engine users get (every rule form), where this checkout has it
            from space.reasoning import build_engine
        except ImportError:
            pass
        else:
            return build_engine(loaded, owl=False)
        try:  # two layers for a hybrid rule set, where this checkout has them
            from space.reasoning.hybrid import HybridEngine, mixes_forms
        except ImportError:
            return RuleEngine(loaded, owl=False)
        return (HybridEngine if mixes_forms(loaded) else RuleEngine)(loaded, owl=False)

    def closure(rules: Path, data: list[Path]) -> Graph | None:
        try:
            run = engine(rules)
            graph = Graph()
            for path in data:  # the referee's fixed base, as tests/test_jena_conformance.py
                kind = guess_format(str(path)) or "turtle"
                graph.parse(path, format=kind, publicID="http://jena.test/data/" + path.name)
            run.load(graph)
        except Exception:  # as above: no answer
            return None
        return run.graph

    def states(rules: Path, steps: list[str]) -> list[Graph] | None:
        try:
            run = engine(rules)
            run.load(Graph())
            found = []
            for step in steps:
                if step == "=":
                    found.append(Graph() + run.graph)
                    continue
                triple = next(iter(ntriples(step[2:])))
                run.apply(**{"added" if step[0] == "+" else "removed": [triple]})
        except Exception:  # as above: no answer
            return None
        return found

    def ntriples(text: str) -> Graph:
        graph = Graph()
        for line in text.splitlines():
            s, p, o = _LINE.match(line).groups()  # type: ignore[union-attr]
            graph.add((from_n3(s), from_n3(p), from_n3(o)))  # type: ignore[arg-type]
        return graph

    texts = json.loads((JENA / "rule_texts.json").read_text())
    accepted = [t for t in texts if t["jena"].startswith("ok")]
    files = sorted((JENA / "etc").glob("*.rules"))
    rows: list[list[object]] = [
        [
            "rule texts in Jena's tests that Jena parses: parsed",
            sum(parses(t["text"]) for t in accepted),
            len(accepted),
        ],
        ["bundled rule files: parsed", sum(parses(f.read_text()) for f in files), len(files)],
    ]
    same = total = 0
    answering = set()
    for expected in sorted((JENA / "expected").glob("*.nt")):
        answer = expected.read_text()
        if answer.startswith(("error", "timeout")):
            continue
        rules, data = expected.stem.split("@")
        total += 1
        ours = closure(JENA / "etc" / f"{rules}.rules", [JENA / "data" / f for f in DATA[data]])
        if ours is not None and isomorphic(ours, ntriples(answer)):
            same += 1
            answering.add(rules)
    rows.append(["bundled rule files on Jena's test data: closures as Jena's", same, total])
    cases = sorted((JENA / "cases").glob("*.json"))
    passed = 0
    for case in cases:
        answer = case.with_suffix(".expected.nt").read_text()
        spec = json.loads(case.read_text())
        if "steps" in spec:
            jena = [ntriples(p) for p in re.split(r"^# state \d+\n", answer, flags=re.M)[1:]]
            got = states(case.with_suffix(".rules"), spec["steps"])
            passed += (
                got is not None
                and len(got) == len(jena)
                and all(isomorphic(a, b) for a, b in zip(got, jena, strict=True))
            )
            continue
        ours = closure(case.with_suffix(".rules"), [case.with_suffix(".data.nt")])
        passed += ours is not None and isomorphic(ours, ntriples(answer))
    rows.append(["transcribed Jena test cases: answer as Jena", passed, len(cases)])
    print_table(
        f"Jena's rule material through {root}", ["material", "yes (count)", "of (count)"], rows
    )
    print(f"closures as Jena's from {len(answering)} files: {', '.join(sorted(answering))}")


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("root", nargs="?", type=Path, default=HERE, help="holds `space`")
    main(parse(parser).root.resolve())
