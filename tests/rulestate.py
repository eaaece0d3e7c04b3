"""A rule engine over the project's ontology, driven the way agents write into the space."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from rdflib import Graph
from rdflib.term import Node

from space.reasoning import RuleEngine

REPO = Path(__file__).resolve().parents[1]


class RuledState:
    """The engine with `rules`, loaded with `data`; `set` replaces a single-valued state.

    `fired` lists the production rules fired by every `set`, in order.
    """

    def __init__(self, rules: str | Sequence[str], data: Graph) -> None:
        names = [rules] if isinstance(rules, str) else rules
        self.engine = RuleEngine.from_files(
            rules=[REPO / "rules" / name for name in names],
            ontology=[REPO / "ontology" / "selfconfig.ttl"],
        )
        self.engine.load(data)
        self.fired: list[str] = []

    def set(self, subject: Node, predicate: Node, value: Node | None) -> None:
        old = [(subject, predicate, o) for o in self.engine.graph.objects(subject, predicate)]
        added = [] if value is None else [(subject, predicate, value)]
        delta = self.engine.apply(added=added, removed=[t for t in old if t not in added])
        self.fired += [f.rule for f in delta.firings]

    def get(self, subject: Node, predicate: Node) -> Node | None:
        values = sorted(self.engine.graph.objects(subject, predicate))
        assert len(values) <= 1, f"{predicate} of {subject} has several values: {values}"
        return values[0] if values else None
