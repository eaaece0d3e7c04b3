"""Hold encoded triples with the three indexes joins need: SPO, POS and OSP.

The index dicts are created once and never replaced, because compiled join
code holds direct references to them. A leaf (the ids under two keys) is a
tuple while small, a set beyond `SMALL`: most leaves hold one id (an OSP
leaf is the predicates between two nodes), and a set of one is 216 bytes
against a tuple's 48. Readers only iterate a leaf or test `in`, which both do.
"""

from __future__ import annotations

from collections.abc import Iterator

Id = int
T = tuple[int, int, int]
Leaf = tuple[int, ...] | set[int]
Index = dict[int, dict[int, Leaf]]
SMALL = 8  # ids in a tuple leaf: `in` scans it, adding copies it


def _put(index: Index, a: int, b: int, c: int) -> None:
    """Index a triple not yet in the store (a tuple leaf does not check for repeats)."""
    inner = index.get(a)
    if inner is None:
        index[a] = {b: (c,)}
        return
    leaf = inner.get(b)
    if leaf is None:
        inner[b] = (c,)
    elif type(leaf) is not tuple:
        leaf.add(c)
    elif len(leaf) < SMALL:
        inner[b] = (*leaf, c)
    else:
        inner[b] = {*leaf, c}


def _drop(index: Index, a: int, b: int, c: int) -> None:
    """Unindex a triple in the store (so `c` is in its leaf)."""
    inner = index[a]
    leaf = inner[b]
    if type(leaf) is tuple:
        if len(leaf) > 1:  # most leaves hold one id: no tuple rebuilt for them
            i = leaf.index(c)
            inner[b] = leaf[:i] + leaf[i + 1 :]
            return
    else:
        leaf.discard(c)
        if leaf:
            return
    del inner[b]
    if not inner:
        del index[a]


class TripleStore:
    """Keep a set of encoded triples, indexed by subject, predicate and object."""

    def __init__(self) -> None:
        self.triples: set[T] = set()
        self.spo: Index = {}
        self.pos: Index = {}
        self.osp: Index = {}

    def __len__(self) -> int:
        return len(self.triples)

    def __contains__(self, triple: object) -> bool:
        return triple in self.triples

    def __iter__(self) -> Iterator[T]:
        return iter(self.triples)

    def add(self, t: T) -> bool:
        """Add a triple; return False if it was already there."""
        if t in self.triples:
            return False
        self.triples.add(t)
        s, p, o = t
        _put(self.spo, s, p, o)
        _put(self.pos, p, o, s)
        _put(self.osp, o, s, p)
        return True

    def remove(self, t: T) -> bool:
        """Remove a triple; return False if it was not there."""
        if t not in self.triples:
            return False
        self.triples.discard(t)
        s, p, o = t
        _drop(self.spo, s, p, o)
        _drop(self.pos, p, o, s)
        _drop(self.osp, o, s, p)
        return True

    def exists(self, s: Id | None, p: Id | None, o: Id | None) -> bool:
        """Tell whether some triple matches; None matches anything."""
        return next(self.match(s, p, o), None) is not None

    def replace(self, old: T, new: T) -> None:
        """Remove `old` (in the store) and add `new` (not in it): a production firing's drop
        and assertion. The new triple is indexed first, so that a key whose only triple
        is replaced (a setting's POS entry) keeps its dictionary instead of a new one; a
        new object for a subject and predicate with one replaces its SPO leaf."""
        triples = self.triples
        triples.discard(old)
        triples.add(new)
        s, p, o = new
        a, b, c = old
        spo, pos, osp = self.spo, self.pos, self.osp
        objects = spo[s].get(p) if s == a and p == b else None
        if objects is not None and len(objects) == 1:  # (c,) or {c}
            spo[s][p] = (o,)
        else:
            _put(spo, s, p, o)
            _drop(spo, a, b, c)
        _put(pos, p, o, s)
        _drop(pos, b, c, a)
        _put(osp, o, s, p)
        _drop(osp, c, a, b)

    def match(self, s: Id | None, p: Id | None, o: Id | None) -> Iterator[T]:
        """Yield the triples that match; None matches anything."""
        if s is not None:
            by_p = self.spo.get(s, {})
            for p2, objects in by_p.items() if p is None else [(p, by_p.get(p, ()))]:
                for o2 in objects if o is None else ([o] if o in objects else []):
                    yield (s, p2, o2)
        elif p is not None:
            by_o = self.pos.get(p, {})
            for o2, subjects in by_o.items() if o is None else [(o, by_o.get(o, ()))]:
                for s2 in subjects:
                    yield (s2, p, o2)
        elif o is not None:
            for s2, predicates in self.osp.get(o, {}).items():
                for p2 in predicates:
                    yield (s2, p2, o)
        else:
            yield from self.triples
