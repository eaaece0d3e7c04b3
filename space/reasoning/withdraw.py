"""Withdraw what a backward rule with `noValue` concluded once no match of it holds.

Jena answers a backward rule afresh at each query, so a conclusion resting on `noValue`
goes as soon as the triple it waits the absence of appears.
Here a backward rule runs forward, and one with such a test runs as a production rule:
its conclusion is asserted when it fires and would stay. This keeps, for each conclusion
such a rule asserted, the matches that concluded it; after each update the engine
retracts the conclusions none of whose matches holds any more (its triples gone, or a
test false). The rule is woken again when its test may hold again: `noValue` when a
triple goes, `countLiteralValues` (in a backward rule) when a counted triple comes or
goes (`RuleIndex`). That costs, per update, what such conclusions there are: few (Jena's
OWL rule sets have a handful of such rules, the paper's rules none).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from space.reasoning.builtins import Context
from space.reasoning.compile import CompiledRule
from space.reasoning.triples import T

Match = tuple[CompiledRule, tuple[T, ...], tuple]


_WOKEN = frozenset({"noValue", "countLiteralValues"})  # tests that wake their rule again


def withdrawable(compiled: CompiledRule) -> bool:
    """Tell whether a backward rule's conclusions can follow its matches: a production rule
    whose only non-monotonic tests wake it again when they may hold again (`noValue` on a
    removal, `countLiteralValues` on any change of the counted values: `RuleIndex`)."""
    guards = compiled.guards
    return compiled.production and bool(guards) and all(b.name in _WOKEN for b, _ in guards)


class Withdrawals:
    """The conclusions of the given (backward, non-monotonic) rules, with their matches."""

    def __init__(self, orders: Iterable[int]) -> None:
        self.orders = frozenset(orders)
        self._held: dict[T, list[Match]] = {}

    def note(
        self,
        compiled: CompiledRule,
        premises: tuple[T, ...],
        bindings: tuple,
        heads: Iterable[T],
        asserted_by: Mapping[T, object],
    ) -> None:
        """Remember a firing's match for each head it asserted (not those held otherwise)."""
        if compiled.order not in self.orders:
            return
        by, match = (compiled.order, premises), (compiled, premises, bindings)
        for head in heads:
            if head in self._held:
                self._held[head].append(match)
            elif asserted_by.get(head) == by:
                self._held[head] = [match]

    def known(self, compiled: CompiledRule, premises: tuple[T, ...], bindings: tuple) -> bool:
        """Tell whether this match of a held rule already concluded (a wake-up found it again)."""
        return any(
            m[0] is compiled and m[1] == premises and m[2] == bindings
            for matches in self._held.values()
            for m in matches
        )

    def stale(self, triples: set[T], asserted: set[T], ctx: Context) -> list[T]:
        """Return the held conclusions no match of which holds now (and forget them)."""
        gone: list[T] = []
        for head, matches in list(self._held.items()):
            if head not in asserted:  # retracted another way: nothing to withdraw
                del self._held[head]
                continue
            live = [m for m in matches if _holds(m, triples, ctx)]
            if live:
                self._held[head] = live
            else:
                del self._held[head]
                gone.append(head)
        return gone


def _holds(match: Match, triples: set[T], ctx: Context) -> bool:
    compiled, premises, bindings = match
    if not triples.issuperset(premises):
        return False
    return all(b.run(ctx, args(bindings)) is not None for b, args in compiled.guards)
