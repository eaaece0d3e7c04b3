"""Read the W3C OWL 2 test cases (`all.rdf`) and judge the engine on one.

A case is judged as the OWL 2 conformance document says for a forward
reasoner: an entailment's conclusion (blank nodes read as existential
variables) must be in the closure of the premise; an inconsistent premise
must give a conflict; a consistent one, or a negative entailment, none.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from rdflib import OWL, RDF, BNode, Graph, Literal, Namespace
from rdflib.term import Node

from space.reasoning import RuleEngine

TEST = Namespace("http://www.w3.org/2007/OWL/testOntology#")
ALL = Path(__file__).resolve().parents[2] / "shared" / "owl2-tests" / "all.rdf"
if not ALL.exists():  # a worktree beside the shared folder, or the project in it
    ALL = Path(__file__).resolve().parents[3] / "shared" / "owl2-tests" / "all.rdf"

KINDS = (
    ("positive", TEST.PositiveEntailmentTest),
    ("negative", TEST.NegativeEntailmentTest),
    ("inconsistent", TEST.InconsistencyTest),
    ("consistent", TEST.ConsistencyTest),
)


@dataclass(frozen=True)
class Case:
    """One test case: its identifier, what it checks, and its ontologies as RDF/XML text."""

    identifier: str
    kinds: frozenset[str]
    premise: str
    conclusion: str | None
    non_conclusion: str | None
    rl: bool


def read_cases(path: Path = ALL) -> list[Case]:
    """Return every case with an RDF/XML premise, in identifier order."""
    g = Graph()
    g.parse(path, format="xml")
    cases = []
    for case in g.subjects(RDF.type, TEST.TestCase):
        premise = g.value(case, TEST.rdfXmlPremiseOntology)
        if premise is None:
            continue
        types = set(g.objects(case, RDF.type))
        conclusion = g.value(case, TEST.rdfXmlConclusionOntology)
        non_conclusion = g.value(case, TEST.rdfXmlNonConclusionOntology)
        cases.append(
            Case(
                identifier=str(g.value(case, TEST.identifier)),
                kinds=frozenset(name for name, kind in KINDS if kind in types),
                premise=str(premise),
                conclusion=None if conclusion is None else str(conclusion),
                non_conclusion=None if non_conclusion is None else str(non_conclusion),
                rl=TEST.RL in set(g.objects(case, TEST.profile)),
            )
        )
    return sorted(cases, key=lambda c: c.identifier)


def parse(text: str) -> Graph:
    """Parse one ontology of a case (RDF/XML)."""
    g = Graph()
    g.parse(data=text, format="xml")
    return g


def reason(case: Case) -> RuleEngine:
    """Return an engine loaded with the case's premise (as ontology and as data)."""
    engine = RuleEngine([], parse(case.premise))
    engine.load([])
    return engine


def entailed(engine: RuleEngine, conclusion: Graph) -> bool:
    """Tell whether the closure holds the conclusion, its blank nodes read as variables."""
    wanted = [t for t in conclusion if not (t[1] == RDF.type and t[2] == OWL.Ontology)]
    wanted.sort(key=lambda t: sum(isinstance(x, BNode) for x in t))
    return any(True for _ in _solve(engine, wanted, {}))


def _solve(engine: RuleEngine, todo: list, bound: dict[Node, Node]) -> Iterator[None]:
    if not todo:
        yield None
        return
    first, rest = todo[0], todo[1:]
    pattern = [bound.get(x, None if isinstance(x, BNode) else x) for x in first]
    if all(x is not None for x in pattern):
        if _holds(engine, tuple(pattern)):
            yield from _solve(engine, rest, bound)
        return
    for found in list(engine.match(*pattern)):
        new = dict(bound)
        if all(_bind(new, want, got) for want, got in zip(first, found, strict=True)):
            yield from _solve(engine, rest, new)


def _holds(engine: RuleEngine, triple: tuple) -> bool:
    if triple in engine:
        return True
    s, p, o = triple
    return isinstance(o, Literal) and any(_same_literal(o, t[2]) for t in engine.match(s, p))


def _same_literal(a: Literal, b: Node) -> bool:
    return isinstance(b, Literal) and a.eq(b)


def _bind(bound: dict[Node, Node], want: Node, got: Node) -> bool:
    if not isinstance(want, BNode):
        return True
    if want in bound:
        return bound[want] == got
    bound[want] = got
    return True


def judge(case: Case) -> tuple[bool, str]:
    """Run one case; return whether it passed and, if not, why."""
    engine = reason(case)
    conflicts = list(getattr(engine, "conflicts", list)())
    problems = []
    if "inconsistent" in case.kinds and not conflicts:
        problems.append("inconsistency not detected")
    if "consistent" in case.kinds and conflicts:
        problems.append(f"conflict in a consistent ontology: {conflicts[0]}")
    if "positive" in case.kinds and case.conclusion is not None:
        if not entailed(engine, parse(case.conclusion)):
            problems.append("conclusion not entailed")
    if "negative" in case.kinds and case.non_conclusion is not None:
        if entailed(engine, parse(case.non_conclusion)):
            problems.append("non-conclusion entailed")
    return not problems, "; ".join(problems)
