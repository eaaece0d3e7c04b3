"""Order production-rule activations: rule file order first, then most recent first."""

from __future__ import annotations

import heapq
from collections import Counter, deque

from space.reasoning.compile import CompiledRule
from space.reasoning.errors import RuleLoopError
from space.reasoning.joins import Match

Activation = tuple[int, int, CompiledRule, Match]
"""A production rule matched (rule order, -recency, rule, match); it fires if the match holds."""


class Agenda:
    """Queue activations once per match and stop a rule set that keeps firing.

    Args:
        max_firings: how many firings one update may take before it is a loop.
    """

    def __init__(self, max_firings: int) -> None:
        self.max_firings = max_firings
        self._heap: list[Activation] = []
        self._pending: set[tuple[int, tuple]] = set()
        self._seq = 0
        self._total = 0
        self._recent: deque[str] = deque(maxlen=max(10, max_firings // 10))

    def __bool__(self) -> bool:
        return bool(self._heap)

    def push(self, rule: CompiledRule, match: Match) -> None:
        """Queue a match, unless the same match is already waiting."""
        key = (rule.order, match[0])
        if key in self._pending:
            return
        self._pending.add(key)
        self._seq += 1
        heapq.heappush(self._heap, (rule.order, -self._seq, rule, match))

    def pop(self) -> Activation | None:
        """Take the next activation (the caller checks it still holds), or None when empty."""
        if not self._heap:
            return None
        activation = heapq.heappop(self._heap)
        self._pending.discard((activation[0], activation[3][0]))
        return activation

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
        self._heap.clear()
        self._pending.clear()
        self._total = 0
        self._recent.clear()
