"""Order production-rule activations: rule file order first, then most recent first."""

from __future__ import annotations

import heapq
from collections import Counter, deque

from space.reasoning.compile import CompiledRule
from space.reasoning.errors import RuleLoopError
from space.reasoning.joins import Match

Activation = tuple[CompiledRule, Match]
"""A production rule matched; it fires if the match still holds."""


class Agenda:
    """Queue activations once per match and stop a rule set that keeps firing.

    The waiting matches of each rule are a stack (the most recent on top), and a
    heap holds the orders of the rules with some waiting: the heap moves when a
    rule gets its first match or loses its last, not on every match.

    Args:
        max_firings: how many firings one update may take before it is a loop.
    """

    def __init__(self, max_firings: int) -> None:
        self.max_firings = max_firings
        self._orders: list[int] = []  # a heap
        self._waiting: dict[int, tuple[CompiledRule, list[Match]]] = {}
        self._pending: set[tuple[int, tuple]] = set()
        self._total = 0
        self._recent: deque[str] = deque(maxlen=max(10, max_firings // 10))

    def __bool__(self) -> bool:
        return bool(self._orders)

    def push(self, rule: CompiledRule, match: Match) -> None:
        """Queue a match, unless the same match is already waiting."""
        order = rule.order
        pending = self._pending
        waiting_before = len(pending)
        pending.add((order, match[0]))
        if len(pending) == waiting_before:  # (one hash of the premises, not two)
            return
        waiting = self._waiting.get(order)
        if waiting is None:
            self._waiting[order] = (rule, [match])
            heapq.heappush(self._orders, order)
        else:
            waiting[1].append(match)

    def pop(self) -> Activation | None:
        """Take the next activation (the caller checks it still holds), or None when empty."""
        orders = self._orders
        if not orders:
            return None
        order = orders[0]
        rule, stack = self._waiting[order]
        match = stack.pop()
        if not stack:
            del self._waiting[order]
            heapq.heappop(orders)
        self._pending.discard((order, match[0]))
        return rule, match

    def count(self, rule: CompiledRule) -> None:
        """Count one firing.

        Raises:
            RuleLoopError: this update fired more than `max_firings` times.
        """
        self._total += 1
        self._recent.append(rule.label)
        if self._total > self.max_firings:
            window = Counter(self._recent)
            names = tuple(name for name, _ in window.most_common())
            listed = ", ".join(f"{n} ({window[n]}x)" for n in names)
            firings = "firing" if self.max_firings == 1 else "firings"
            raise RuleLoopError(
                f"rules keep firing: more than {self.max_firings} {firings} in one update;"
                f" the last {len(self._recent)} were {listed}",
                names,
            )

    def reset(self) -> None:
        """Forget pending activations and firing counts, before an update."""
        self._orders.clear()
        self._waiting.clear()
        self._pending.clear()
        self._total = 0
        self._recent.clear()
