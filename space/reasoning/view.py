"""Show an engine's state as a read-only rdflib Graph that reads the engine live.

Every lookup goes through `RuleEngine.match` and its indexes, so reading
after an update costs what is read, never a copy of the whole state (a copy
took 3 s at 100k triples).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from rdflib import Graph
from rdflib.store import Store
from rdflib.term import Literal, Node, URIRef

if TYPE_CHECKING:
    from space.reasoning.engine import RuleEngine


class EngineStore(Store):
    """Answer rdflib's store calls from a rule engine; refuse writes."""

    context_aware = False
    formula_aware = False
    transaction_aware = False
    graph_aware = False

    def __init__(self, engine: RuleEngine) -> None:
        super().__init__()
        self._engine = engine
        self._prefixes: dict[str, URIRef] = {}

    def triples(  # type: ignore[override]
        self, triple_pattern: tuple[Node | None, Node | None, Node | None], context: Any = None
    ) -> Iterator[tuple[tuple[Node, Node, Node], Iterator[Any]]]:
        """Yield the engine's triples that match, as rdflib's stores do."""
        s, p, o = triple_pattern
        if not (_plain(s) and _plain(p) and _plain(o)):
            raise TypeError("the engine's graph view matches terms or None, not paths or graphs")
        for triple in self._engine.match(s, p, o):
            # A rule may put a literal where RDF allows none (as in Jena): not in a Graph.
            if isinstance(triple[0], Literal) or not isinstance(triple[1], URIRef):
                continue
            yield triple, iter(())  # type: ignore[misc]

    def __len__(self, context: Any = None) -> int:
        return self._engine.count()

    def add(self, *args: Any, **kwargs: Any) -> None:
        """Refuse: the view is read-only (assert triples with `RuleEngine.apply`)."""
        raise TypeError("the engine's graph is a read-only view: use RuleEngine.apply")

    def remove(self, *args: Any, **kwargs: Any) -> None:
        """Refuse: the view is read-only (retract triples with `RuleEngine.apply`)."""
        raise TypeError("the engine's graph is a read-only view: use RuleEngine.apply")

    def contexts(self, triple: Any = None) -> Iterator[Any]:
        """Yield nothing: the view has no named graphs."""
        return iter(())

    def bind(self, prefix: str, namespace: URIRef, override: bool = True) -> None:
        """Remember a prefix for serialising."""
        if override or prefix not in self._prefixes:
            self._prefixes[prefix] = namespace

    def namespace(self, prefix: str) -> URIRef | None:
        """Return the namespace of a prefix."""
        return self._prefixes.get(prefix)

    def prefix(self, namespace: URIRef) -> str | None:
        """Return the prefix of a namespace."""
        return next((p for p, n in self._prefixes.items() if n == namespace), None)

    def namespaces(self) -> Iterator[tuple[str, URIRef]]:
        """Yield the prefixes bound."""
        yield from self._prefixes.items()


def live_graph(engine: RuleEngine) -> Graph:
    """Return a read-only Graph over the engine's current state."""
    return Graph(store=EngineStore(engine))


def _plain(term: object) -> bool:
    return term is None or isinstance(term, Node)
