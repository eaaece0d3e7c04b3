"""Run a rule set with backward rules in two layers, as Jena's hybrid mode.

In Jena's FBRuleReasoner the forward rules run to a closure over the data alone; the
backward rules (and the rules nested in forward heads, which Jena adds to its backward
engine) answer over that closure and never feed the forward rules. Here the forward
layer is one engine (with OWL RL, if any); the backward layer is a second engine,
sharing its term table, whose input is the forward layer's whole state (functor values
included) and whose state is what this engine answers. Both layers are incremental: an
update passes the forward layer's net change on to the backward layer. With Jena's
bundled `rdfs-fb` and OWL rule sets this gives Jena's closure; one engine with every
rule gives more (forward rules would see what backward rules conclude).

`build_engine` is the one entry point that runs every rule form: a plain `RuleEngine`
for forward rules only (the paper's rules pay nothing), two layers when there are
backward or nested rules.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from rdflib import Graph
from rdflib.term import Node

from space.reasoning.builtins import Registry, default_registry
from space.reasoning.checks import mark_shared_names
from space.reasoning.conflicts import Conflict
from space.reasoning.delta import Delta, Origin, TripleChange, Why
from space.reasoning.engine import RuleEngine
from space.reasoning.errors import RuleLoopError
from space.reasoning.parser import load_rules
from space.reasoning.rdffiles import read_graph
from space.reasoning.rules import Rule
from space.reasoning.terms import TermTable
from space.reasoning.triples import T
from space.terms import TextTriple, Triple


def mixes_forms(rules: Sequence[Rule]) -> bool:
    """Return whether a rule set has both forward and backward rules (Jena's hybrid case)."""
    return any(r.backward for r in rules) and any(not r.backward for r in rules)


def has_backward(rules: Sequence[Rule]) -> bool:
    """Return whether a rule set needs the backward layer (a backward or nested rule)."""
    return any(r.backward for r in rules)


class HybridEngine:
    """Two layers: forward rules (and OWL RL) over the data, backward rules over their closure.

    Offers `RuleEngine`'s reading and updating calls, with the same `Delta` and
    `RuleLoopError` contract. Not thread-safe (as `RuleEngine`).
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
        rules = mark_shared_names(rules)  # a name shared across the layers labels both
        terms = TermTable()  # shared: one id per term, one set of hidden nodes
        common = {"registry": registry, "max_firings": max_firings, "printer": printer}
        self.forward = RuleEngine(
            [r for r in rules if not r.backward], ontology, owl=owl, terms=terms, **common
        )
        self.backward = RuleEngine(
            [r for r in rules if r.backward], owl=False, terms=terms, **common
        )
        self.rules = (*self.forward.rules, *self.backward.rules)
        self.registry = registry
        self.terms = terms

    @property
    def graph(self) -> Graph:
        """Return the current state as a live, read-only rdflib Graph (see `RuleEngine.graph`)."""
        return self.backward.graph

    def triples(self, origin: Origin | None = None) -> Iterator[Triple]:
        """Yield the current triples, or only the asserted or only the inferred ones.

        Asserted means asserted in the forward layer (by a caller or a production rule);
        what backward rules conclude is inferred.
        """
        if origin is None:
            yield from self.backward.triples()
            return
        asserted, want = self.forward._asserted, origin is Origin.ASSERTED
        shown, decode = self.terms.shown, self.terms.triple
        for t in self.backward._store:
            if shown(t) and (t in asserted) == want:
                yield decode(t)  # type: ignore[misc]

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
        return self._both(lambda: self.forward.load(triples))

    def apply(self, added: Iterable[Triple] = (), removed: Iterable[Triple] = ()) -> Delta:
        """Retract, assert, run both layers; return the net change (see `RuleEngine.apply`).

        Raises:
            InputError: a triple is not an RDF triple of rdflib terms.
            RuleLoopError: production rules of either layer kept firing; as
                `RuleEngine.apply`, their firings are undone and `kept` is what stays.
        """
        return self._both(lambda: self.forward.apply(added, removed))

    def apply_texts(
        self, added: Iterable[Sequence[str]] = (), removed: Iterable[Sequence[str]] = ()
    ) -> Delta:
        """`apply` on N-Triples texts, the `Delta` in texts (see `RuleEngine.apply_texts`)."""
        return self._both(lambda: self.forward.apply_texts(added, removed), texts=True)

    def match_texts(
        self, subject: str | None = None, predicate: str | None = None, obj: str | None = None
    ) -> Iterator[TextTriple]:
        """`match` with the pattern and the triples as N-Triples texts."""
        return self.backward.match_texts(subject, predicate, obj)

    def holds_texts(self, subject: str, predicate: str, obj: str) -> bool:
        """`triple in engine` for a triple given as N-Triples texts."""
        return self.backward.holds_texts(subject, predicate, obj)

    def why(self, triple: Triple) -> Why | None:
        """Return why a triple holds, from the layer that concluded it."""
        found = self.backward.why(triple)
        if found is not None and found.asserted and found.rule is None:
            return self.forward.why(triple)
        return found

    def _both(self, first_layer: Callable[[], Delta], *, texts: bool = False) -> Delta:
        """Run the forward layer, pass its net change to the backward layer, merge the two
        (with `texts`, the triples as N-Triples texts)."""
        loop: RuleLoopError | None = None
        try:
            first = first_layer()
        except RuleLoopError as exc:
            loop, first = exc, exc.kept  # type: ignore[assignment]
        plus, minus = self.forward._log.net()
        try:
            second = self.backward._apply_ids(plus, minus)
        except RuleLoopError as exc:
            loop, second = loop or exc, exc.kept  # type: ignore[assignment]
        delta = self._merge(first, second, self.terms.text_triple if texts else self.terms.triple)
        if loop is not None:
            loop.kept = delta
            raise loop
        return delta

    def _merge(self, first: Delta, second: Delta, decode: Callable[[T], Triple]) -> Delta:
        """Return the net change of the whole state: present in the backward layer's state,
        asserted when asserted in the forward layer (as `ChangeLog.delta` for one engine);
        its triples as `decode` gives them."""
        forward_before, backward_before = self.forward._log.before, self.backward._log.before
        asserted, present = self.forward._asserted, self.backward._store.triples
        shown = self.terms.shown
        added: list[TripleChange] = []
        removed: list[TripleChange] = []
        inferred: tuple[list[Triple], list[Triple]] = ([], [])
        touched: dict[T, None] = dict.fromkeys(forward_before)
        touched.update(dict.fromkeys(backward_before))
        for t in touched:
            if not shown(t):
                continue
            was_present = backward_before[t][0] if t in backward_before else t in present
            was_asserted = forward_before[t][1] if t in forward_before else t in asserted
            is_present, is_asserted = t in present, t in asserted
            triple: Triple = decode(t)  # type: ignore[assignment]
            if is_present != was_present:
                now = is_asserted if is_present else was_asserted
                change = TripleChange(triple, Origin.ASSERTED if now else Origin.INFERRED)
                (added if is_present else removed).append(change)
            was_inferred = was_present and not was_asserted
            if (is_present and not is_asserted) != was_inferred:
                inferred[1 if was_inferred else 0].append(triple)
        return Delta(
            added=tuple(added),
            removed=tuple(removed),
            asserted_added=first.asserted_added,
            asserted_removed=first.asserted_removed,
            inferred_added=tuple(inferred[0]),
            inferred_removed=tuple(inferred[1]),
            firings=(*first.firings, *second.firings),
        )


Engine = RuleEngine | HybridEngine


def build_engine(
    rules: Sequence[Rule],
    ontology: Graph | Iterable[Triple] | None = None,
    **options: Any,
) -> Engine:
    """Return the engine that runs every form in the rules: one layer for forward rules only,
    two (`HybridEngine`) when there are backward or nested rules. Options as `RuleEngine`'s.

    Raises:
        RuleError: a rule cannot be compiled.
    """
    kind = HybridEngine if has_backward(rules) else RuleEngine
    return kind(rules, ontology, **options)


def engine_from_files(
    rules: Iterable[str | Path] = (),
    ontology: Iterable[str | Path] = (),
    **options: Any,
) -> Engine:
    """Build an engine from files as `RuleEngine.from_files`, with `build_engine`'s choice.

    Raises:
        RuleSyntaxError, RuleError: a rules file is invalid.
        InputError: an ontology file cannot be read or parsed.
    """
    registry = options.pop("registry", None) or default_registry()
    warn = options.pop("warn", None)
    parsed = load_rules(rules, registry, **({} if warn is None else {"warn": warn}))
    return build_engine(parsed, read_graph(ontology), registry=registry, **options)
