"""Remember how each inferred triple was derived, so deletions retract exactly what they must.

Every derivation (rule, premises) is kept, so deletion is delete-and-rederive
(DRed) without re-running rules: over-delete everything a deleted triple helped
derive, then put back whatever still has a derivation whose premises all stand,
starting from the triples that were never touched. This is right for recursive
rules (transitivity, sameAs) where counting alone would keep cycles alive.

Most triples have one derivation and most premises support one triple, so
an entry is held bare while it is one, a list up to `SMALL`, a set beyond
(a set of one is 216 bytes: at 100k triples it was a third of the engine's
memory). `each` reads all three.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Hashable, Sequence
from typing import TypeVar

from space.reasoning.triples import SMALL, T, TripleStore

Derivation = tuple[int, tuple[T, ...]]
Item = TypeVar("Item", bound=Hashable)  # a tuple: a Derivation or a triple
Entry = Item | list[Item] | set[Item]


def each(held: Entry[Item] | None) -> Collection[Item]:
    """Return what one entry holds as a collection (a bare item as a 1-tuple)."""
    if held is None:
        return ()
    return (held,) if type(held) is tuple else held  # type: ignore[return-value]


def add(mapping: dict[T, Entry[Item]], key: T, item: Item) -> None:
    """Add `item` to `key`'s entry (again is harmless)."""
    held = mapping.get(key)
    if held is None:
        mapping[key] = item
    elif type(held) is tuple:
        if held != item:
            mapping[key] = [held, item]
    elif type(held) is list:
        if item not in held:
            if len(held) < SMALL:
                held.append(item)
            else:
                mapping[key] = {*held, item}
    else:
        held.add(item)  # type: ignore[union-attr]


def discard(mapping: dict[T, Entry[Item]], key: T, item: Item) -> None:
    """Take `item` out of `key`'s entry; an entry left empty goes."""
    held = mapping.get(key)
    if held is None:
        return
    if type(held) is tuple:
        if held == item:
            del mapping[key]
        return
    if type(held) is list:
        if item in held:
            held.remove(item)
    else:
        held.discard(item)  # type: ignore[union-attr]
    if not held:
        del mapping[key]


class Support:
    """Hold the derivations of triples and which triples each premise supports.

    Each entry is bare, a list or a set (see the module's docstring): read it with `each`.
    """

    def __init__(self) -> None:
        self.derivations: dict[T, Entry[Derivation]] = {}
        self.dependents: dict[T, Entry[T]] = {}

    def record(self, triple: T, rule: int, premises: tuple[T, ...]) -> None:
        """Remember that `rule` derived `triple` from `premises` (again is harmless)."""
        add(self.derivations, triple, (rule, premises))
        dependents = self.dependents
        for premise in premises:
            add(dependents, premise, triple)

    def first(self, triple: T) -> Derivation | None:
        """Return one derivation of a triple (the smallest, for a stable answer), or None."""
        found = self.derivations.get(triple)
        return min(each(found)) if found else None

    def retract(
        self,
        doomed: Sequence[T],
        store: TripleStore,
        asserted: set[T],
        touch: Callable[[T], None],
    ) -> list[T]:
        """Delete triples no longer asserted, and what they alone supported.

        `doomed` must already be out of `asserted`, and touched. `touch` is
        called before any other triple leaves the store. Returns the triples
        that are gone for good, in the order they were reached.
        """
        triples = store.triples
        if len(doomed) == 1:  # a firing's drop: no list built for it
            (only,) = doomed
            if only not in triples:
                return []
            if only not in self.dependents:
                return self._retract_leaf(only, store)
        stack = [t for t in doomed if t in triples]
        over: dict[T, None] = {}
        while stack:
            triple = stack.pop()
            if triple in over or triple in asserted:
                continue
            over[triple] = None
            stack.extend(each(self.dependents.get(triple)))
        for triple in over:
            touch(triple)
            store.remove(triple)
        self._rederive(over, store)
        gone = [t for t in over if t not in triples]
        self._forget(gone)
        return gone

    def _retract_leaf(self, triple: T, store: TripleStore) -> list[T]:
        """Retract one triple that supports nothing: the common case, kept cheap.

        What `_forget` does for it, inlined: it has no dependents to walk.
        """
        held = self.derivations.get(triple)
        if held is not None:  # (a dropped triple, asserted, mostly has no derivation)
            found = each(held)
            triples = store.triples
            if any(triples.issuperset(p) for _, p in found):
                return []
            del self.derivations[triple]
            dependents = self.dependents
            for _, premises in found:
                for premise in premises:
                    discard(dependents, premise, triple)
        store.remove(triple)  # no touch: the caller touched the doomed
        return [triple]

    def _rederive(self, over: dict[T, None], store: TripleStore) -> None:
        """Put back over-deleted triples that still have a derivation on standing premises."""
        triples = store.triples
        queue = list(over)
        while queue:
            triple = queue.pop()
            if triple in triples:
                continue
            for _, premises in each(self.derivations.get(triple)):
                if all(p in triples for p in premises):
                    store.add(triple)
                    queue.extend(d for d in each(self.dependents.get(triple)) if d in over)
                    break

    def _forget(self, gone: list[T]) -> None:
        """Drop the derivations of gone triples and those that used them.

        A derivation dropped from a triple that stays is dropped from its other
        premises' dependents too, unless another of its derivations uses them.
        """
        gone_set = set(gone)
        derivations, dependents = self.derivations, self.dependents
        for triple in gone:
            for _, premises in each(derivations.pop(triple, None)):
                for premise in premises:
                    discard(dependents, premise, triple)
        for triple in gone:
            for user in each(dependents.pop(triple, None)):
                if user in gone_set:
                    continue
                dropped = [d for d in each(derivations.get(user)) if triple in d[1]]
                for d in dropped:
                    discard(derivations, user, d)
                kept = {p for _, premises in each(derivations.get(user)) for p in premises}
                for premise in {p for _, premises in dropped for p in premises}:
                    if premise not in kept and premise not in gone_set:
                        discard(dependents, premise, user)
