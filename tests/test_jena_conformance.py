"""Jena's own rule tests, rule sets and test data, with the answers Jena 4.5 gave.

The answers were recorded by `bench/jena_referee.py` (rerun it to refresh them);
Jena is not needed here. A case that differs must be listed in KNOWN with the
reason (docs/rules.md, "Differences from Jena"), and the test pins that it
still differs, so a fix shows up as a failure to update the list.
"""

from __future__ import annotations

import json
import logging
import re
import zipfile
from pathlib import Path

import pytest
from rdflib import Graph
from rdflib.compare import isomorphic
from rdflib.util import from_n3, guess_format

from space.reasoning import (
    Engine,
    RuleError,
    build_engine,
    default_registry,
    load_rules,
    parse_rules,
)

JENA = Path(__file__).parent / "data" / "jena"
REG = default_registry()
DATA = {
    "rdfs-tbox1-data1": ("rdfs-tbox1.rdf", "rdfs-data1.rdf"),
    "rdfs-tbox1-data3": ("rdfs-tbox1.rdf", "rdfs-data3.rdf"),
    "owl-tbox-consistent": ("owl-tbox.owl", "owl-consistentData.rdf"),
}

# Rule texts of Jena's tests that Jena parses and this engine refuses, and why.
REFUSED_TEXTS = {
    "TestBasics.java:114": "arity checked when the rule is built (Jena: when it fires)",
    "TestBasics.java:118": "arity checked when the rule is built (Jena: when it fires)",
    "TestBasics.java:253": "arity checked when the rule is built (Jena: when it fires)",
    "TestBasics.java:254": "arity checked when the rule is built (Jena: when it fires)",
    "TestBasics.java:256": "arity checked when the rule is built (Jena: when it fires)",
    "TestBasics.java:257": "arity checked when the rule is built (Jena: when it fires)",
    "TestBugs.java:796": "someTriple is a builtin the Jena test registers itself",
}

# Cases where this engine's answer differs from Jena's, and why (docs/rules.md).
KNOWN: dict[str, str] = {}
KNOWN["basics_rebind"] = (
    "Jena's plain forward engine keeps conclusions when a premise is removed (the test rebinds "
    "instead); here removing a premise retracts what it supported"
)
KNOWN["hybrid_nested_and_hide"] = (
    "a rule nested in a head: Jena keeps the instance rule, and what it concludes, after its "
    "parent's match goes (its second state); here they go with it"
)
KNOWN["bugs_empty_remove"] = (
    "remove(0) of a triple an axiom concludes: Jena deletes it (and what follows) once; here it "
    "keeps its derivation, so it stays"
)


def _quiet(message: str) -> None:
    """Swallow duplicate-name warnings: Jena's files have many."""


def _texts() -> list[dict[str, str]]:
    return json.loads((JENA / "rule_texts.json").read_text())


def test_every_rule_text_jena_parses_is_parsed_here_but_the_documented_ones():
    accepted = [t for t in _texts() if t["jena"].startswith("ok")]
    refused = {}
    for entry in accepted:
        try:
            parse_rules(entry["text"], REG, warn=_quiet)
        except RuleError as exc:
            refused[entry["source"]] = str(exc)
    assert set(refused) == set(REFUSED_TEXTS), refused
    assert len(accepted) - len(refused) >= 200


def test_rule_texts_jena_refuses_are_refused_here_too():
    for entry in _texts():
        if entry["jena"].startswith("ok"):
            continue
        with pytest.raises(RuleError):
            parse_rules(entry["text"], REG, warn=_quiet)


def _closures() -> list[str]:
    return sorted(p.stem for p in (JENA / "expected").glob("*.nt"))


@pytest.mark.parametrize("case", _closures())
def test_bundled_rule_set_on_jena_test_data_answers_as_jena(case, caplog):
    caplog.set_level(logging.ERROR)
    rules_name, data_name = case.split("@")
    answer = (JENA / "expected" / f"{case}.nt").read_text()
    rules_file = JENA / "etc" / f"{rules_name}.rules"
    if answer.startswith(("error", "timeout")):
        pytest.skip(f"Jena gives no closure: {answer.splitlines()[0][:80]}")
    ours = _run(rules_file, [JENA / "data" / f for f in DATA[data_name]])
    jena = _ntriples(answer)
    assert isomorphic(ours, jena), _diff(ours, jena)


def _cases() -> list[str]:
    return sorted(p.stem for p in (JENA / "cases").glob("*.json"))


@pytest.mark.parametrize("case", _cases())
def test_transcribed_jena_test_case_answers_as_jena(case, caplog):
    caplog.set_level(logging.ERROR)
    folder = JENA / "cases"
    answer = (folder / f"{case}.expected.nt").read_text()
    spec = json.loads((folder / f"{case}.json").read_text())
    if "steps" in spec:
        states = _states(folder / f"{case}.rules", spec["steps"])
        jenas = [_ntriples(part) for part in re.split(r"^# state \d+\n", answer, flags=re.M)[1:]]
        pairs = list(zip(states, jenas, strict=True))
    else:
        pairs = [(_run(folder / f"{case}.rules", [folder / f"{case}.data.nt"]), _ntriples(answer))]
    same = all(isomorphic(ours, jena) for ours, jena in pairs)
    if case in KNOWN:
        assert not same, f"{case} now answers as Jena: update KNOWN and docs"
    else:
        for ours, jena in pairs:
            assert isomorphic(ours, jena), _diff(ours, jena)


def _states(rules: Path, steps: list[str]) -> list[Graph]:
    """Apply the case's steps (`+ triple`, `- triple`, `=`); return the closure at each `=`."""
    engine = _engine(rules)
    engine.load(Graph())
    states = []
    for step in steps:
        if step == "=":
            states.append(_copy(engine.graph))
            continue
        triple = next(iter(_ntriples(step[2:])))
        if step[0] == "+":
            engine.apply(added=[triple])
        else:
            engine.apply(removed=[triple])
    return states


def _copy(graph: Graph) -> Graph:
    out = Graph()
    for triple in graph:
        out.add(triple)
    return out


_LINE = re.compile(r"^(<[^>]*>|_:\S+)\s+(<[^>]*>)\s+(.*\S)\s*\.$")


def _ntriples(text: str) -> Graph:
    """Read Jena's N-Triples, which may hold relative IRIs (`<n1>`, as Jena's tests write)."""
    graph = Graph()
    for line in text.splitlines():
        s, p, o = _LINE.match(line).groups()  # type: ignore[union-attr]
        graph.add((from_n3(s), from_n3(p), from_n3(o)))  # type: ignore[arg-type]
    return graph


def _engine(rules: Path) -> Engine:
    """As Jena's GenericRuleReasoner: two layers when there are backward rules (as the
    reasoner agent and `tspace reason` build it)."""
    return build_engine(load_rules([rules], REG, warn=_quiet), owl=False)


BASE = "http://jena.test/data/"  # as the referee reads the data, wherever the checkout is


def _read(paths: list[Path]) -> Graph:
    """Read Jena's test data with the base the referee used (relative IRIs resolve alike)."""
    graph = Graph()
    for path in paths:
        graph.parse(path, format=guess_format(str(path)) or "turtle", publicID=BASE + path.name)
    return graph


def _run(rules: Path, data: list[Path]) -> Graph:
    engine = _engine(rules)
    engine.load(_read(data))
    return engine.graph


def _diff(ours: Graph, jena: Graph) -> str:
    only_ours = sorted(t for t in ours if t not in jena)[:10]
    only_jena = sorted(t for t in jena if t not in ours)[:10]
    return f"only here: {only_ours}\nonly in Jena: {only_jena}"


def test_bundled_rule_files_parse_but_the_two_jena_cannot_run():
    parsed, refused = [], {}
    for path in sorted((JENA / "etc").glob("*.rules")):
        try:
            load_rules([path], REG, warn=_quiet)
            parsed.append(path.stem)
        except RuleError as exc:
            refused[path.stem] = str(exc)
    # owl-b: Jena refuses it too (a `*` wildcard); owl: Jena parses it but cannot run it
    # (no builtin `contradiction`), and this engine refuses unknown builtins when reading.
    assert set(refused) == {"owl-b", "owl"}, refused
    assert "wildcard variables" in refused["owl-b"]
    assert "unknown builtin 'contradiction'" in refused["owl"]
    assert len(parsed) == 13


def test_include_of_a_jena_rule_set_reads_it_from_jenas_jar(tmp_path, monkeypatch):
    jar = tmp_path / "jena-core-test.jar"
    with zipfile.ZipFile(jar, "w") as archive:
        archive.write(JENA / "etc" / "rdfs-fb.rules", "etc/rdfs-fb.rules")
    monkeypatch.setenv("TSPACE_JENA_CORE", str(jar))
    rules = tmp_path / "mine.rules"
    rules.write_text("@include <RDFS>.\n[mine: (?a rdf:type eg:C) -> (?a rdf:type eg:D)]\n")
    loaded = load_rules([rules], REG, warn=_quiet)
    assert loaded[-1].name == "mine"
    assert {r.name for r in loaded} >= {"rdfs7b", "rdfs2", "rdfs9"}
    assert loaded[0].where.file.endswith("etc/rdfs-fb.rules")


def test_include_of_a_jena_rule_set_without_jena_says_what_to_install(tmp_path, monkeypatch):
    monkeypatch.setenv("TSPACE_JENA_CORE", str(tmp_path / "none.jar"))
    monkeypatch.setattr("space.reasoning.rulesets._jars", lambda: [tmp_path / "none.jar"])
    with pytest.raises(RuleError, match=r"t.rules:1:1: @include <OWLMini> needs Jena's "):
        parse_rules("@include <OWLMini>.", REG, source="t.rules")
