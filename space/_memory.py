"""An rdflib in-memory store with bulk updates, for the copies of a space kept in memory.

The store's state and every agent's view apply each change to an rdflib graph.
Through `Graph.add`/`Graph.remove` a triple costs several microseconds (checks,
a pattern search per removal), so a 600-triple change cost milliseconds in
every process. `BulkMemory` is rdflib's `SimpleMemory` (graphs over it read,
and answer SPARQL, as before) plus `has` and `update`, which work on its
indexes directly.
"""

from __future__ import annotations

from collections.abc import Iterable

from rdflib.plugins.stores.memory import SimpleMemory
from rdflib.term import Node

from space.terms import Triple


class BulkMemory(SimpleMemory):
    """`SimpleMemory` with O(1) membership and bulk removal and addition.

    Uses `SimpleMemory`'s three indexes (`spo`, `pos`, `osp`: dicts of dicts
    of dicts); tests/test_memory.py checks it against rdflib's own methods.
    """

    def __init__(self) -> None:
        super().__init__()
        self._spo: dict = self._SimpleMemory__spo  # type: ignore[attr-defined]
        self._pos: dict = self._SimpleMemory__pos  # type: ignore[attr-defined]
        self._osp: dict = self._SimpleMemory__osp  # type: ignore[attr-defined]

    def has(self, triple: Triple) -> bool:
        """Return True if the store holds the triple (all three terms given)."""
        s, p, o = triple
        return o in self._spo.get(s, _EMPTY).get(p, _EMPTY)

    def objects_of(self, s: Node, p: Node) -> list[Node]:
        """Return the objects of (s, p), unsorted."""
        return list(self._spo.get(s, _EMPTY).get(p, _EMPTY))

    def subjects_of(self, p: Node, o: Node | None) -> list[Node]:
        """Return the subjects of (p, o), or of p with any object when `o` is None; unsorted."""
        by_object = self._pos.get(p, _EMPTY)
        if o is not None:
            return list(by_object.get(o, _EMPTY))
        return list(dict.fromkeys(s for subjects in by_object.values() for s in subjects))

    def update(self, removed: Iterable[Triple] = (), added: Iterable[Triple] = ()) -> None:
        """Remove triples (absent ones are ignored), then add triples."""
        discard, put = self.discard, self.put
        for triple in removed:
            discard(triple)
        for triple in added:
            put(triple)

    def discard(self, triple: Triple) -> None:
        """Remove one triple if present, and the index entries it leaves empty.

        rdflib's own removal keeps them: a reading rewritten every tick left one
        per old value, so a long-running agent's copy grew without end.
        """
        s, p, o = triple
        objects = self._spo.get(s, _EMPTY).get(p, _EMPTY)
        if o in objects:
            _drop(self._spo, s, p, o)
            _drop(self._pos, p, o, s)
            _drop(self._osp, o, s, p)

    def put(self, triple: Triple) -> None:
        """Add one triple (no-op if present)."""
        s, p, o = triple
        po = self._spo.get(s)
        if po is None:
            po = self._spo[s] = {}
        objects = po.get(p)
        if objects is None:
            objects = po[p] = {}
        if o in objects:
            return
        objects[o] = 1
        os_ = self._pos.get(p)
        if os_ is None:
            os_ = self._pos[p] = {}
        subjects = os_.get(o)
        if subjects is None:
            subjects = os_[o] = {}
        subjects[s] = 1
        sp = self._osp.get(o)
        if sp is None:
            sp = self._osp[o] = {}
        predicates = sp.get(s)
        if predicates is None:
            predicates = sp[s] = {}
        predicates[p] = 1

    def remove(self, triple_pattern: tuple, context: object = None) -> None:
        """Remove what matches a pattern; a whole triple without a search."""
        s, p, o = triple_pattern
        if s is None or p is None or o is None:
            for triple, _ in list(self.triples(triple_pattern, context)):  # type: ignore[arg-type]
                self.discard(triple)
        else:
            self.discard(triple_pattern)  # type: ignore[arg-type]


def _drop(index: dict, a: Node, b: Node, c: Node) -> None:
    """Delete `index[a][b][c]`, then `index[a][b]` and `index[a]` if that left them empty."""
    inner = index[a]
    leaves = inner[b]
    del leaves[c]
    if not leaves:
        del inner[b]
        if not inner:
            del index[a]


_EMPTY: dict = {}
