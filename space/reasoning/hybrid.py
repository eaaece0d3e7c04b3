"""Run a rule set that mixes forward and backward rules in two layers, as Jena's hybrid mode.

In Jena's FBRuleReasoner the forward rules run to a closure over the data alone; the
backward rules (and the rules nested in forward heads, which Jena adds to its backward
engine) answer over that closure and never feed the forward rules. Here the forward
layer is one engine; the backward layer is a second engine, sharing its term table,
whose input is the forward layer's whole state (functor values included) and whose
state is what this engine answers. With Jena's bundled `rdfs-fb` rule sets this gives
Jena's closure; one engine with every rule gives more (forward rules would see what
backward rules conclude).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from rdflib import Graph
from rdflib.term import Node

from space.reasoning.builtins import Registry, default_registry
from space.reasoning.conflicts import Conflict
from space.reasoning.delta import Delta, Origin, TripleChange, Why
from space.reasoning.engine import RuleEngine, read_graph
from space.reasoning.parser import load_rules
from space.reasoning.rules import Rule
from space.reasoning.terms import TermTable
from space.terms import Triple


def mixes_forms(rules: Sequence[Rule]) -> bool:
    """Return whether a rule set has both forward and backward rules (Jena's hybrid case)."""
    return any(r.backward for r in rules) and any(not r.backward for r in rules)


class HybridEngine:
    """Two layers: forward rules over the data, backward rules over the forward closure.

    Offers `RuleEngine`'s reading and updating calls. Not thread-safe (as `RuleEngine`).
    """

    def __init__(
        self,
        rules: Sequence[Rule],
        ontology: Graph | Iterable[Triple] | None = None,
        *,
        registry: Registry | None = None,
        owl: bool = True,
        max_firings: int = 10_000,
        printer: Callable[[str], None] = print,
    ) -> None:
        registry = registry or default_registry()
        terms = TermTable()
        common = {"registry": registry, "max_firings": max_firings, "printer": printer}
        self.forward = RuleEngine(
            [r for r in rules if not r.backward], ontology, owl=owl, terms=terms, **common
        )
        self.backward = RuleEngine(
            [r for r in rules if r.backward], owl=False, terms=terms, **common
        )
        self.rules = (*self.forward.rules, *self.backward.rules)
        self.terms = terms

    @property
    def graph(self) -> Graph:
        """Return the current state as an rdflib Graph; do not modify it."""
        return self.backward.graph

    def triples(self, origin: Origin | None = None) -> Iterator[Triple]:
        """Yield the current triples, or only the asserted or only the inferred ones."""
        for triple in self.backward.triples():
            if origin is None or (self._asserted(triple) == (origin is Origin.ASSERTED)):
                yield triple

    def match(
        self, subject: Node | None = None, predicate: Node | None = None, obj: Node | None = None
    ) -> Iterator[Triple]:
        """Yield the current triples that match a pattern (None matches anything)."""
        return self.backward.match(subject, predicate, obj)

    def __contains__(self, triple: object) -> bool:
        return triple in self.backward

    def count(self) -> int:
        """Return how many triples the state holds (asserted and inferred)."""
        return self.backward.count()

    def conflicts(self) -> tuple[Conflict, ...]:
        """Return the OWL 2 RL conflicts that hold now (the ontology is the forward layer's)."""
        return self.forward.conflicts()

    def load(self, triples: Graph | Iterable[Triple] = ()) -> Delta:
        """Assert the initial state and run both layers (see `RuleEngine.load`)."""
        first = self.forward.load(triples)
        return self._pass_on(first)

    def apply(self, added: Iterable[Triple] = (), removed: Iterable[Triple] = ()) -> Delta:
        """Retract, assert, run both layers; return the net change (see `RuleEngine.apply`)."""
        first = self.forward.apply(added, removed)
        return self._pass_on(first)

    def why(self, triple: Triple) -> Why | None:
        """Return why a triple holds, from the layer that concluded it."""
        found = self.backward.why(triple)
        if found is not None and found.asserted and found.rule is None:
            return self.forward.why(triple)
        return found

    def _asserted(self, triple: Triple) -> bool:
        found = self.forward.why(triple)
        return found is not None and found.asserted

    def _pass_on(self, first: Delta) -> Delta:
        plus, minus = self.forward._log.net()
        second = self.backward._apply_ids(plus, minus)

        def origin(change: TripleChange) -> TripleChange:
            asserted = change.triple in first.asserted_added or self._asserted(change.triple)
            return TripleChange(change.triple, Origin.ASSERTED if asserted else Origin.INFERRED)

        added = tuple(origin(c) for c in second.added)
        return Delta(
            added=added,
            removed=second.removed,
            asserted_added=first.asserted_added,
            asserted_removed=first.asserted_removed,
            inferred_added=tuple(c.triple for c in added if c.origin is Origin.INFERRED),
            inferred_removed=tuple(c.triple for c in second.removed),
            firings=(*first.firings, *second.firings),
        )


def engine_from_files(
    rules: Iterable[str | Path] = (),
    ontology: Iterable[str | Path] = (),
    **options: Any,
) -> RuleEngine | HybridEngine:
    """Build an engine from files as `RuleEngine.from_files`, in two layers when the rules mix
    forward and backward rules (Jena's hybrid mode).

    Raises:
        RuleSyntaxError, RuleError: a rules file is invalid.
        InputError: an ontology file cannot be read or parsed.
    """
    registry = options.pop("registry", None) or default_registry()
    parsed = load_rules(rules, registry)
    kind = HybridEngine if mixes_forms(parsed) else RuleEngine
    return kind(parsed, read_graph(ontology), registry=registry, **options)
