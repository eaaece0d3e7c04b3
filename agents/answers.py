"""Changes another per-robot reasoner owes an answer to, so none is lost when it dies.

Every per-robot reasoner applies every change; one answers it (`agents.ownership`).
The others note the change's conclusions here until they see that answer in the
space. When its reasoner leaves (its liveliness token goes: stopped, or killed)
before answering, the roster names another one; that one writes what the lost
answer should have said, as its own engine holds it now. Writing the engine's
present truth for those triples, not the old delta, keeps later changes to the
same triples right, and makes a late copy of the lost answer harmless.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from rdflib.term import Node

from space import TextTriple, text_of
from space.reasoning import Delta, Engine, Origin

OWED_FOR = 60.0  # seconds: an owner alive this long after a change answers it itself or resyncs


@dataclass
class Owed:
    """One change's conclusions, owed by another reasoner.

    Attributes:
        id: the change's id (the answer names it as its cause).
        seq: its place in the store's order.
        robot: the robot it concerned (None: shared, the leader's).
        delta: what this reasoner's engine concluded from it.
        since: when it was noted (monotonic seconds).
    """

    id: str
    seq: int
    robot: Node | None
    delta: Delta
    since: float = field(default_factory=time.monotonic)


class Ledger:
    """The answers owed by other reasoners, oldest first (the agent's thread only)."""

    def __init__(self) -> None:
        self._owed: dict[str, Owed] = {}

    def __len__(self) -> int:
        return len(self._owed)

    def note(self, change_id: str, seq: int, robot: Node | None, delta: Delta) -> None:
        """Remember a change another reasoner answers; nothing to owe if it concluded nothing."""
        d = delta
        if d.asserted_added or d.asserted_removed or d.inferred_added or d.inferred_removed:
            self._owed[change_id] = Owed(change_id, seq, robot, delta)

    def answered(self, cause: str | None) -> None:
        """Forget the change an answer seen in the space names."""
        if cause is not None:
            self._owed.pop(cause, None)

    def take(self, mine: Callable[[Node | None, int], bool]) -> list[Owed]:
        """Remove and return the owed answers `mine(robot, seq)` now says are this reasoner's.

        Those older than `OWED_FOR` are dropped: their owner is alive and answered, or
        saw its answer refused and resynchronised.
        """
        now, taken = time.monotonic(), []
        for owed in list(self._owed.values()):
            if mine(owed.robot, owed.seq):
                taken.append(self._owed.pop(owed.id))
            elif now - owed.since > OWED_FOR:
                del self._owed[owed.id]
        return taken


def present_truth(engine: Engine, deltas: Iterable[Delta]) -> Delta:
    """Return what the engine holds now of the triples these deltas changed, as one delta.

    The deltas' triples are N-Triples texts (`Engine.apply_texts`), and so are its.
    """
    asserted = set(map(text_of, engine.triples(Origin.ASSERTED)))
    inferred = set(map(text_of, engine.triples(Origin.INFERRED)))
    touched_a: dict[TextTriple, None] = {}
    touched_i: dict[TextTriple, None] = {}
    firings = []
    for delta in deltas:
        touched_a.update(dict.fromkeys((*delta.asserted_added, *delta.asserted_removed)))
        touched_i.update(dict.fromkeys((*delta.inferred_added, *delta.inferred_removed)))
        firings += delta.firings
    return Delta(
        asserted_added=tuple(t for t in touched_a if t in asserted),
        asserted_removed=tuple(t for t in touched_a if t not in asserted),
        inferred_added=tuple(t for t in touched_i if t in inferred),
        inferred_removed=tuple(t for t in touched_i if t not in inferred),
        firings=tuple(firings),
    )
