"""Order production-rule activations: rule file order first, then most recent first."""

from __future__ import annotations

import heapq
from collections import Counter
from collections.abc import Iterable, Sequence

from space.reasoning.compile import CompiledRule
from space.reasoning.delta import Firing
from space.reasoning.errors import RuleLoopError
from space.reasoning.joins import Match
from space.reasoning.triples import T

Activation = tuple[CompiledRule, Match]
"""A production rule matched; it fires if the match still holds."""


class Agenda:
    """Queue activations once per match and stop a rule set that keeps firing.

    The waiting matches of each rule are a stack (the most recent on top), a match
    alone while it is the only one (most rules wait on one at a time: no list made),
    and a heap holds the orders of the rules with some waiting: the heap moves when a
    rule gets its first match or loses its last, not on every match. A match waits
    once: `_pending` maps its premises to the order of the rule that waits on them (a
    set of orders in the rare case of two rules with equal premises), so a push keeps
    no new tuple alive for the collector.

    Args:
        max_firings: how many firings one update may take before it is a loop.
        rules: the engine's rules, each at its order.
    """

    def __init__(self, max_firings: int, rules: Sequence[CompiledRule]) -> None:
        self.max_firings = max_firings
        self._rules = rules
        self._orders: list[int] = []  # a heap
        self._waiting: dict[int, Match | list[Match]] = {}  # order -> match or stack
        self._pending: dict[tuple[T, ...], int | set[int]] = {}

    def __bool__(self) -> bool:
        return bool(self._orders)

    def push(self, activations: Iterable[Activation]) -> None:
        """Queue matches, each unless the same match is already waiting.

        All a join found in one call (a batch's: one per rule; `zip(repeat(rule), matches)`
        for one rule's), so that a batch of N rules costs one call, not N.
        """
        pending, waiting_of, orders = self._pending, self._waiting, self._orders
        for rule, match in activations:
            order = rule.order
            premises = match[0]
            size = len(pending)
            held = pending.setdefault(premises, order)
            if len(pending) == size:  # some rule waits on these premises already
                if held == order or (type(held) is set and order in held):
                    continue
                pending[premises] = {held, order} if type(held) is int else held | {order}
            waiting = waiting_of.get(order)
            if waiting is None:
                waiting_of[order] = match
                heapq.heappush(orders, order)
            elif type(waiting) is list:
                waiting.append(match)
            else:
                waiting_of[order] = [waiting, match]

    def pop(self) -> Activation | None:
        """Take the next activation (the caller checks it still holds), or None when empty."""
        orders = self._orders
        if not orders:
            return None
        order = orders[0]
        waiting = self._waiting[order]
        if type(waiting) is list:
            match = waiting.pop()
            if not waiting:
                del self._waiting[order]
                heapq.heappop(orders)
        else:
            match = waiting
            del self._waiting[order]
            heapq.heappop(orders)
        premises = match[0]
        held = self._pending.pop(premises)
        if type(held) is set:
            held.discard(order)
            self._pending[premises] = held.pop() if len(held) == 1 else held
        return self._rules[order], match

    def loop(self, firings: Sequence[Firing], rule: CompiledRule) -> RuleLoopError:
        """Return the error for an update about to fire `rule` after `max_firings` firings
        (the engine counts them: its list of this update's `firings`), naming the last ones."""
        window = max(10, self.max_firings // 10)
        recent = [f.rule for f in firings[max(0, len(firings) - window + 1) :]] + [rule.label]
        counts = Counter(recent)
        names = tuple(name for name, _ in counts.most_common())
        listed = ", ".join(f"{n} ({counts[n]}x)" for n in names)
        firings_ = "firing" if self.max_firings == 1 else "firings"
        return RuleLoopError(
            f"rules keep firing: more than {self.max_firings} {firings_} in one update;"
            f" the last {len(recent)} were {listed}",
            names,
        )

    def reset(self) -> None:
        """Forget pending activations, before an update."""
        self._orders.clear()
        self._waiting.clear()
        self._pending.clear()
