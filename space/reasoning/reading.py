"""Reading a rule engine's state: matches, counts, a live graph, conflicts and `why`.

The read half of `RuleEngine`, apart from its updates (`engine.py`): what a
caller may look up between updates, each costing what it reads.
"""

from __future__ import annotations

from collections.abc import Iterator

from rdflib import Graph
from rdflib.term import Node

from space.reasoning.compile import CompiledRule
from space.reasoning.conflicts import Conflict, read_conflicts
from space.reasoning.delta import Origin, Why
from space.reasoning.support import Support
from space.reasoning.terms import TermTable
from space.reasoning.triples import T, TripleStore
from space.reasoning.view import live_graph
from space.terms import TextTriple, Triple


class EngineReads:
    """The state a `RuleEngine` keeps, read: set up by `RuleEngine.__init__`."""

    terms: TermTable
    _store: TripleStore
    _asserted: set[T]
    _asserted_by: dict[T, tuple[int, tuple[T, ...]]]
    _support: Support
    _compiled: list[CompiledRule]
    _graph: Graph | None
    _same: int

    @property
    def graph(self) -> Graph:
        """Return the current state (asserted and inferred) as a live, read-only rdflib Graph.

        It reads the engine through `match` on every lookup: after an update it
        shows the new state at once, and reading costs what is read.
        """
        if self._graph is None:
            self._graph = live_graph(self)
        return self._graph

    def count(self) -> int:
        """Return how many triples the state holds (asserted and inferred)."""
        if self.terms.hidden:  # `hide` was called: count what is listed
            return sum(1 for t in self._store if self.terms.shown(t))
        osp, functors = self._store.osp, self.terms.functors
        unlisted = sum(len(ps) for f in functors for ps in osp.get(f, {}).values())
        return len(self._store) - unlisted

    def triples(self, origin: Origin | None = None) -> Iterator[Triple]:
        """Yield the current triples, or only the asserted or only the inferred ones."""
        functors, hidden = self.terms.functors, self.terms.hidden
        for t in self._store:
            if t[2] in functors or t[0] in functors:
                continue
            if hidden and (t[0] in hidden or t[1] in hidden or t[2] in hidden):
                continue
            if origin is None or (t in self._asserted) == (origin is Origin.ASSERTED):
                yield self._decode(t)

    def match(
        self, subject: Node | None = None, predicate: Node | None = None, obj: Node | None = None
    ) -> Iterator[Triple]:
        """Yield the current triples that match a pattern (None matches anything).

        Costs what matches, through the indexes: unlike `graph`, nothing is
        rebuilt after an update, so a caller may look things up on every change.
        """
        find = self.terms.find
        ids = [None if x is None else find(x) for x in (subject, predicate, obj)]
        return self._matching(ids, (subject, predicate, obj), self.terms.names)

    def match_texts(
        self, subject: str | None = None, predicate: str | None = None, obj: str | None = None
    ) -> Iterator[TextTriple]:
        """`match` with the pattern and the triples as N-Triples texts."""
        find = self.terms.find_text
        ids = [None if x is None else find(x) for x in (subject, predicate, obj)]
        return self._matching(ids, (subject, predicate, obj), self.terms.texts())

    def holds_texts(self, subject: str, predicate: str, obj: str) -> bool:
        """`triple in engine` for a triple given as N-Triples texts (the state holds it)."""
        find = self.terms.find_text
        ids = (find(subject), find(predicate), find(obj))  # None for a term never seen
        if ids not in self._store.triples:
            return False
        return not self.terms.hidden or self.terms.shown(ids)  # type: ignore[arg-type]

    def _matching(
        self, ids: list[int | None], pattern: tuple[object, ...], names: list
    ) -> Iterator[tuple]:
        """Yield the stored triples matching encoded `ids`, decoded by `names`."""
        if any(i is None and x is not None for i, x in zip(ids, pattern, strict=True)):
            return  # a term the engine never saw: nothing matches
        functors, hidden = self.terms.functors, self.terms.hidden  # as TermTable.shown, inlined
        for s, p, o in self._store.match(*ids):
            if o in functors or s in functors:
                continue
            if hidden and (s in hidden or p in hidden or o in hidden):
                continue
            yield (names[s], names[p], names[o])

    def __contains__(self, triple: object) -> bool:
        ids = tuple(self.terms.find(x) for x in triple) if isinstance(triple, tuple) else ()
        if len(ids) == 3 and ids[0] == ids[2] and ids[0] is not None and ids[1] == self._same:
            return self._in_state(ids[0])  # eq-ref, answered rather than stored
        if len(ids) != 3 or ids not in self._store:
            return False
        return not self.terms.hidden or self.terms.shown(ids)  # type: ignore[arg-type]

    def _in_state(self, term: int) -> bool:
        store = self._store
        return term in store.spo or term in store.pos or term in store.osp

    def conflicts(self) -> tuple[Conflict, ...]:
        """Return the conflicts that hold now (OWL 2 RL rules with head `false`), sorted.

        Costs what the conflicts are. A conflict goes when one of its triples does.
        """
        return read_conflicts(self.terms, self._store, self._support, self._compiled)

    def why(self, triple: Triple) -> Why | None:
        """Return why a triple holds: asserted, or a rule and its premises; None if it does not."""
        t = tuple(self.terms.find(x) for x in triple)
        if t not in self._store:
            return None
        if t in self._asserted:
            by = self._asserted_by.get(t)  # type: ignore[arg-type]
            return Why(True) if by is None else Why(True, *self._explain(by))
        found = self._support.first(t)  # type: ignore[arg-type]
        return Why(False, *self._explain(found)) if found else None

    def _explain(self, derivation: tuple[int, tuple[T, ...]]) -> tuple[str, tuple[Triple, ...]]:
        rule, premises = derivation
        return self._compiled[rule].label, tuple(self._decode(p) for p in premises)

    def _decode(self, t: T) -> Triple:
        return self.terms.triple(t)  # type: ignore[return-value]
