"""Fire production rules: the agenda's activations, one at a time, each fully applied.

The production half of `RuleEngine`'s update (`engine.py`): a popped activation fires
if its match still holds and its tests pass. Most production rules replace one premise
by one new triple (a setting's new value): `_replace` does that without the general
steps of `_fire` (lists of drops and heads, the support walk, a journal call each),
and steps aside to `_fire` whenever the state asks for them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from space.reasoning.agenda import Agenda
from space.reasoning.builtins import Context
from space.reasoning.changes import ChangeLog
from space.reasoning.compile import CompiledRule, RuleIndex
from space.reasoning.delta import NEW_FIRING, Firing
from space.reasoning.joins import Match
from space.reasoning.support import Support
from space.reasoning.terms import TermTable
from space.reasoning.triples import T, TripleStore
from space.reasoning.withdraw import Withdrawals
from space.terms import Triple

By = tuple[int, tuple[T, ...]]


class EngineFirings:
    """The firing of production rules, on a `RuleEngine`'s state (set up by its `__init__`)."""

    terms: TermTable
    _store: TripleStore
    _asserted: set[T]
    _asserted_by: dict[T, By]
    _support: Support
    _agenda: Agenda
    _index: RuleIndex
    _log: ChangeLog
    _ctx: Context
    _firings: list[Firing]
    _withdrawals: Withdrawals | None
    _out: list[Match]
    _triple: Callable[[T], Triple]
    _assert: Callable[[Iterable[T], By | None], None]
    _unassert: Callable[..., None]
    _propagate: Callable[[list[T]], None]
    _take: Callable[[CompiledRule | None, list, list[T]], None]

    def _run_agenda(self) -> None:
        """Fire activations one at a time while their match still holds."""
        triples, ctx, agenda = self._store.triples, self._ctx, self._agenda
        firings, limit = self._firings, agenda.max_firings  # this update's: its count
        while (activation := agenda.pop()) is not None:
            compiled, (premises, bindings) = activation
            if not triples.issuperset(premises):
                continue
            if not compiled.replaces:  # which has no guard and is not held
                guards = compiled.guards
                if guards and any(b.run(ctx, args(bindings)) is None for b, args in guards):
                    continue
                held = self._withdrawals
                if held is not None and compiled.order in held.orders:
                    if held.known(compiled, premises, bindings):
                        continue  # woken again on a match that concluded already
            if len(firings) >= limit:
                raise agenda.loop(firings, compiled)
            if compiled.replaces:
                self._replace(compiled, premises, bindings)
            else:
                self._fire(compiled, premises, bindings)

    def _fire(self, compiled: CompiledRule, premises: tuple[T, ...], bindings: tuple) -> None:
        """Fire a rule: its actions, then drops and removals, then its heads, each propagated."""
        heads = compiled.heads(bindings)
        # Most production rules only drop: build no empty lists, no tuples twice.
        pick = premises.__getitem__
        dropped = tuple(map(pick, compiled.drops)) if compiled.drops else ()
        removed = tuple(map(pick, compiled.removes)) if compiled.removes else ()
        for builtin, args in compiled.actions:
            builtin.act(self._ctx, args(bindings))
        if dropped:
            self._unassert(dropped, notify=False)
        if removed:
            self._unassert(removed, notify=True)
        self._assert(heads, (compiled.order, premises))
        if self._withdrawals is not None:
            self._withdrawals.note(compiled, premises, bindings, heads, self._asserted_by)
        functors = self.terms.functors
        asserted = tuple(t for t in heads if t[2] not in functors) if functors else heads
        retracted = dropped + removed if removed else dropped
        record = (compiled.label, premises, asserted, retracted, self._triple)
        self._firings.append(NEW_FIRING(Firing, record))

    def _replace(self, compiled: CompiledRule, premises: tuple[T, ...], bindings: tuple) -> None:
        """Fire a rule that `replaces` one premise by its head: `_fire`, one triple out and
        one in, without its general steps (no support to walk, no lists, one journal call).

        `_fire` when the dropped triple is not a plain asserted leaf (it supports or has
        a derivation) or the head is not new: their general steps are then the point.
        """
        made = compiled.heads(bindings)
        (head,) = made
        old = premises[compiled.drops[0]]
        asserted, support, triples = self._asserted, self._support, self._store.triples
        if (
            old not in asserted
            or head in triples  # (what is asserted is in the store)
            or old in support.dependents
            or old in support.derivations
        ):
            self._fire(compiled, premises, bindings)
            return
        by = (compiled.order, premises)
        asserted_by = self._asserted_by
        self._log.replaced(old, asserted_by.pop(old, None), head, by)
        asserted.discard(old)
        asserted.add(head)
        asserted_by[head] = by
        self._store.replace(old, head)
        # `_propagate([head])`, its first step here: most heads start one join, which fails.
        s, p, o = head
        out, queue = self._out, []
        for rule, trigger in self._index.starts(p, o):
            trigger(s, p, o, out)
            if out:
                self._take(rule, out, queue)
        if queue:
            self._propagate(queue)
        functors = self.terms.functors
        if functors and head[2] in functors:
            made = ()
        record = (compiled.label, premises, made, (old,), self._triple)
        self._firings.append(NEW_FIRING(Firing, record))
