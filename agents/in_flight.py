"""The reasoner's answers sent but not yet acknowledged, read back in order.

A backlog of changes (after a cut) is answered without a round trip to the
store each: answers are sent at once and their acknowledgements read later,
oldest first, at most `IN_FLIGHT` outstanding. Kept apart from the reasoner
because waiting out a slow store is a concern of its own: an answer the store
is only slow to acknowledge is sent again, never taken for a refusal.
"""

from __future__ import annotations

import logging
import threading
from collections import deque

from space import Changeset, Pending, SpaceError, SpaceTimeout, TripleSpace

IN_FLIGHT = 64  # answers sent, not yet acknowledged, at most


class InFlight:
    """Answers sent without waiting, oldest first (the agent's thread only)."""

    def __init__(self, timeout: float, stopping: threading.Event, log: logging.Logger) -> None:
        self._timeout = timeout
        self._stopping = stopping
        self._log = log
        self._unacked: deque[tuple[Changeset, Pending]] = deque()

    def send(self, ts: TripleSpace, cs: Changeset) -> int:
        """Send `cs` without waiting; return how many answers are outstanding past
        `IN_FLIGHT`, the oldest ones the caller is to `settle` now.
        """
        self._unacked.append((cs, ts.send_later(cs, timeout=self._timeout)))
        return max(0, len(self._unacked) - IN_FLIGHT)

    def settle(self, ts: TripleSpace, count: int | None = None, *, wait: bool = True) -> bool:
        """Read the acknowledgements of `count` answers (all by default), oldest first.

        Without `wait`, only those already in: from the oldest up to the first one
        still on its way.

        Returns:
            True when the store did not take one; then every answer in flight is
            read, and the caller's engine is ahead of the space.
        """
        lost = False
        while self._unacked and (count is None or count > 0):
            if not wait and not self._unacked[0][1].ready():
                break
            cs, pending = self._unacked.popleft()
            try:
                self._acknowledged(ts, cs, pending)
            except SpaceError as exc:
                self._log.warning("answer to change %s not taken: %s", cs.cause, exc)
                lost = True
            if count is not None:
                count -= 1
        if lost:
            self.settle(ts)
        return lost

    def _acknowledged(self, ts: TripleSpace, cs: Changeset, pending: Pending) -> None:
        """Wait for an answer's acknowledgement, sending it again while the store is only slow.

        A store that answers later than `--timeout` (a backlog of writes ahead of the
        answer) still applies the answer it holds. Taking that for a refusal made the
        reasoner rebuild its engine and skip every change the space then held: those
        changes got one answer naming none of them, seconds late (bench/fleet.py at
        2,000 changesets/s). The same changeset again (its id) is safe: a store answers
        a retried id with the first one's outcome. Stopping ends the wait.

        Raises:
            SpaceError: the store refused it, or none answered, or the agent is stopping.
        """
        while True:
            try:
                pending.result()
                return
            except SpaceTimeout:
                if self._stopping.is_set():
                    raise
                self._log.warning("answer to change %s not acknowledged yet: sent again", cs.cause)
                pending = ts.send_later(cs, timeout=self._timeout)
