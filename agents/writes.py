"""An agent's writes in flight: sent at once, their acknowledgements read off the loop.

A control loop must not wait for the store (up to `--timeout` seconds when it is
away). `Writes` keeps the pipelined changesets and reads their acknowledgements
on a thread of its own, in the order sent; a write the store did not take comes
back through `failed()` for the loop to undo and report.
"""

from __future__ import annotations

import queue
import threading
from dataclasses import dataclass

from space import Pending, SpaceError, Triple


@dataclass(frozen=True)
class Failed:
    """A write the store did not take.

    Attributes:
        id: the changeset's id.
        error: why.
        added: what it added (to undo in the agent's view).
        removed: what it removed.
    """

    id: str
    error: SpaceError
    added: tuple[Triple, ...]
    removed: tuple[Triple, ...]


_Sent = tuple[str, Pending, tuple[Triple, ...], tuple[Triple, ...]]


class Writes:
    """Settle pipelined writes on a thread; hand failures back to the agent's loop."""

    def __init__(self) -> None:
        self._sent: queue.SimpleQueue[_Sent | None] = queue.SimpleQueue()
        self._failed: queue.SimpleQueue[Failed] = queue.SimpleQueue()
        self._in_flight = 0
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, name="agent-writes", daemon=True)
        self._started = False

    def track(
        self, cs_id: str, pending: Pending, added: list[Triple], removed: list[Triple]
    ) -> None:
        """Read `pending`'s acknowledgement later; returns at once."""
        with self._lock:
            self._in_flight += 1
            if not self._started:
                self._started = True
                self._thread.start()
        self._sent.put((cs_id, pending, tuple(added), tuple(removed)))

    @property
    def in_flight(self) -> int:
        """Return how many writes are not acknowledged yet."""
        with self._lock:
            return self._in_flight

    def failed(self) -> list[Failed]:
        """Return the writes that failed since the last call (never blocks)."""
        out = []
        while True:
            try:
                out.append(self._failed.get_nowait())
            except queue.Empty:
                return out

    def close(self, timeout: float) -> None:
        """Wait up to `timeout` seconds for the writes in flight, then stop the thread."""
        self._sent.put(None)
        if self._thread.is_alive():
            self._thread.join(timeout)

    def _run(self) -> None:
        while (item := self._sent.get()) is not None:
            cs_id, pending, added, removed = item
            try:
                pending.result()
            except SpaceError as exc:
                self._failed.put(Failed(cs_id, exc, added, removed))
            finally:
                with self._lock:
                    self._in_flight -= 1
