"""Track what one update touches, to report its net change and to undo it."""

from __future__ import annotations

from space.reasoning.delta import Delta, Firing, Origin, TripleChange
from space.reasoning.terms import TermTable
from space.reasoning.triples import T, TripleStore
from space.terms import Triple

JournalEntry = bool | T | tuple[int, tuple[T, ...]] | None

# (was present, was asserted), indexed by the two tests: no new pair per touch.
_STATES = (((False, False), (False, True)), ((True, False), (True, True)))
_ASSERTED, _INFERRED = Origin.ASSERTED, Origin.INFERRED
_new_change = tuple.__new__  # TripleChange(...) without NamedTuple's Python-level __new__


class ChangeLog:
    """Remember, for each triple an update touches, whether it was present and asserted before.

    The journal lists every assertion (True) and retraction (False) in order, with
    the production rule that made an assertion, so an update can be reversed: three
    items an entry, flat (a tuple per entry was two objects a firing for the collector).
    """

    def __init__(self, terms: TermTable, store: TripleStore, asserted: set[T]) -> None:
        self._terms = terms
        self._store = store
        self._triples = store.triples
        self._asserted = asserted
        self._before: dict[T, tuple[bool, bool]] = {}
        self._expected: dict[T, bool] = {}
        self._fresh: list[T] = []  # a fresh load's triples, noted in `_before` when read
        self.journal: list[JournalEntry] = []

    def begin(self, added: list[T], removed: list[T]) -> None:
        """Start an update in which the caller asserts `added` and retracts `removed`.

        The containers are emptied, not replaced: made once, they leave the collector's
        young generation, which an update growing new ones of 2N entries made every
        collection during it walk again (the cost per firing grew with the rules).
        """
        self._fresh = []
        self._before.clear()
        self.journal.clear()
        self._expected.clear()
        self._expected.update((t, False) for t in removed)
        self._expected.update((t, True) for t in added)

    def touch(self, t: T) -> None:
        """Note the state of a triple before the update first changes it."""
        before = self._before
        if t not in before:
            before[t] = _STATES[t in self._triples][t in self._asserted]

    def replaced(self, old: T, was: tuple | None, new: T, by: tuple[int, tuple[T, ...]]) -> None:
        """Note and journal a production firing that drops `old` (asserted, `was` its rule)
        and asserts `new` (neither present nor asserted): `touch` and the journal, in one call."""
        before = self._before
        if old not in before:
            before[old] = _STATES[True][True]
        if new not in before:
            before[new] = _STATES[False][False]
        self.journal += (False, old, was, True, new, by)

    def fresh(self, triples: list[T]) -> Delta:
        """Return the `delta` of a fresh engine's load of monotonic rules: `triples`, all new.

        As `begin`, the touches and `delta` would give it, in one pass: nothing
        was present, no rule changed what is asserted. The triples are noted as
        touched only if `before` or `net` is read (a HybridEngine's next layer):
        at a million triples that dictionary is 80 MB and a second.
        """
        self.begin([], [])
        self._fresh = triples
        added: list[TripleChange] = []
        inferred: list[Triple] = []
        functors, asserted = self._terms.functors, self._asserted
        hidden, shown, decode = self._terms.hidden, self._terms.shown, self._terms.triple
        for t in triples:
            if t[2] in functors or (hidden and not shown(t)):
                continue
            triple = decode(t)
            if t in asserted:
                added.append(_new_change(TripleChange, (triple, _ASSERTED)))
            else:
                added.append(_new_change(TripleChange, (triple, _INFERRED)))
                inferred.append(triple)
        return Delta(added=tuple(added), inferred_added=tuple(inferred))

    @property
    def before(self) -> dict[T, tuple[bool, bool]]:
        """Return, for each triple this update touched, (was present, was asserted); read only."""
        if self._fresh:
            self._before = dict.fromkeys(self._fresh, (False, False))
            self._fresh = []
        return self._before

    def net(self) -> tuple[list[T], list[T]]:
        """Return the triples (functor-valued ones too) present now and not before, and back."""
        triples, before = self._triples, self.before
        added = [t for t, (was, _) in before.items() if not was and t in triples]
        removed = [t for t, (was, _) in before.items() if was and t not in triples]
        return added, removed

    def delta(self, firings: tuple[Firing, ...], *, texts: bool = False) -> Delta:
        """Return the net change since `begin`: each touched triple's plan (`_PLANS`) by its
        states before and now, and what the caller meant for it; with `texts`, its triples
        as N-Triples texts."""
        out: tuple[list, ...] = ([], [], [], [], [], [])
        triples, asserted, expected = self._triples, self._asserted, self._expected.get
        functors, hidden, shown = self._terms.functors, self._terms.hidden, self._terms.shown
        filtered = bool(functors or hidden)
        names = self._terms.texts() if texts else self._terms.names  # not a call per triple
        plans = _PLANS
        for t, was in self._before.items():
            plan = plans[was, t in triples, t in asserted, expected(t)]
            if plan is None:
                continue
            if filtered and (t[2] in functors or (hidden and not shown(t))):
                continue
            s, p, o = t
            triple = (names[s], names[p], names[o])
            change, origin, by_rule, inferred = plan
            if change >= 0:
                out[change].append(_new_change(TripleChange, (triple, origin)))
            if by_rule >= 0:
                out[by_rule].append(triple)
            if inferred >= 0:
                out[inferred].append(triple)
        return Delta(*map(tuple, out), firings=firings)  # type: ignore[arg-type]


def _plan(
    was_present: bool, was_asserted: bool, is_present: bool, is_asserted: bool, meant: bool | None
) -> tuple[int, Origin | None, int, int] | None:
    """Return where a touched triple goes in a `Delta` (the indexes of its fields in order,
    -1 for none): as a change, with its origin; as asserted or retracted by rules; as
    inferred or no longer. None when it goes nowhere. `meant`: True if the caller
    asserted it, False if the caller retracted it, None if neither."""
    # Checked before the net change: a caller's triple that rules took away in the same
    # update (a loaded one, say) is no net change, but the caller must be told, or it
    # keeps the triple.
    by_rule = is_asserted != (was_asserted if meant is None else meant)
    if is_present == was_present and is_asserted == was_asserted and not by_rule:
        return None
    change, origin = -1, None
    if is_present != was_present:
        now = is_asserted if is_present else was_asserted
        change, origin = (0 if is_present else 1), (_ASSERTED if now else _INFERRED)
    rule = (2 if is_asserted else 3) if by_rule else -1
    was_inferred = was_present and not was_asserted
    is_inferred = is_present and not is_asserted
    inferred = (5 if was_inferred else 4) if is_inferred != was_inferred else -1
    return change, origin, rule, inferred


_PLANS = {
    (was, present, now, meant): _plan(*was, present, now, meant)
    for was in (_STATES[0][0], _STATES[0][1], _STATES[1][0], _STATES[1][1])
    for present in (False, True)
    for now in (False, True)
    for meant in (None, False, True)
}
"""`_plan` of every (before, present now, asserted now, meant) a touched triple can have."""
