"""Remember how each inferred triple was derived, so deletions retract exactly what they must.

Every derivation (rule, premises) is kept, so deletion is delete-and-rederive
(DRed) without re-running rules: over-delete everything a deleted triple helped
derive, then put back whatever still has a derivation whose premises all stand,
starting from the triples that were never touched. This is right for recursive
rules (transitivity, sameAs) where counting alone would keep cycles alive.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from space.reasoning.triples import T, TripleStore

Derivation = tuple[int, tuple[T, ...]]


class Support:
    """Hold the derivations of triples and which triples each premise supports."""

    def __init__(self) -> None:
        self.derivations: dict[T, set[Derivation]] = {}
        self.dependents: dict[T, set[T]] = {}

    def record(self, triple: T, rule: int, premises: tuple[T, ...]) -> None:
        """Remember that `rule` derived `triple` from `premises` (again is harmless)."""
        found = self.derivations.get(triple)
        if found is None:
            self.derivations[triple] = {(rule, premises)}
        else:
            found.add((rule, premises))
        dependents = self.dependents
        for premise in premises:
            users = dependents.get(premise)
            if users is None:
                dependents[premise] = {triple}
            else:
                users.add(triple)

    def first(self, triple: T) -> Derivation | None:
        """Return one derivation of a triple (the smallest, for a stable answer), or None."""
        found = self.derivations.get(triple)
        return min(found) if found else None

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
            if not self.dependents.get(only):
                return self._retract_leaf(only, store)
        stack = [t for t in doomed if t in triples]
        over: dict[T, None] = {}
        while stack:
            triple = stack.pop()
            if triple in over or triple in asserted:
                continue
            over[triple] = None
            stack.extend(self.dependents.get(triple, ()))
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
        found = self.derivations.get(triple)
        if found:
            triples = store.triples
            if any(triples.issuperset(p) for _, p in found):
                return []
            del self.derivations[triple]
            dependents = self.dependents
            for _, premises in found:
                for premise in premises:
                    users = dependents.get(premise)
                    if users is not None:
                        users.discard(triple)
        self.dependents.pop(triple, None)  # an empty set, if any
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
            for _, premises in self.derivations.get(triple, ()):
                if all(p in triples for p in premises):
                    store.add(triple)
                    queue.extend(d for d in self.dependents.get(triple, ()) if d in over)
                    break

    def _forget(self, gone: list[T]) -> None:
        """Drop the derivations of gone triples and those that used them."""
        gone_set = set(gone)
        for triple in gone:
            for _, premises in self.derivations.pop(triple, ()):
                for premise in premises:
                    users = self.dependents.get(premise)
                    if users is not None:
                        users.discard(triple)
        for triple in gone:
            for user in self.dependents.pop(triple, ()):
                if user in gone_set:
                    continue
                found = self.derivations.get(user)
                if found:
                    found.difference_update([d for d in found if triple in d[1]])
                    if not found:
                        del self.derivations[user]
