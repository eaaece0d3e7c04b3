"""Hold a write's acknowledgement until every follower store has it too.

A leader store acknowledges a changeset only once each follower has committed
it (or a deadline passed), so killing the leader right after an
acknowledgement loses nothing.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import zenoh

log = logging.getLogger("tspace.store")


@dataclass
class _Held:
    deadline: float
    space: str
    seq: int
    query: zenoh.Query
    reply_key: str
    payload: bytes


class AckGate:
    """Acknowledgements waiting for followers. Used by the store's worker thread only."""

    def __init__(self, timeout: float = 1.0) -> None:
        self.timeout = timeout
        self.followers: set[str] = set()
        # Stores whose token is alive: each becomes a follower (waited for) with its first
        # confirmation, so a token alone (anyone can declare one) delays no acknowledgement.
        self.candidates: set[str] = set()
        self._acked: dict[str, dict[str, int]] = {}
        self._held: list[_Held] = []

    def hold(self, space: str, seq: int, query: zenoh.Query, key: str, payload: bytes) -> bool:
        """Keep an acknowledgement until the followers have `seq`; False if there are none."""
        if not self.followers:
            return False
        deadline = time.monotonic() + self.timeout
        self._held.append(_Held(deadline, space, seq, query, key, payload))
        return True

    def acked(self, store: str, seqs: dict[str, int]) -> None:
        """Record what a follower has committed."""
        if store not in self.candidates:
            return
        self.followers.add(store)
        known = self._acked.setdefault(store, {})
        for space, seq in seqs.items():
            known[space] = max(seq, known.get(space, 0))

    def forget(self, store: str) -> None:
        """Stop waiting for a follower that is gone."""
        self.followers.discard(store)
        self.candidates.discard(store)
        self._acked.pop(store, None)

    def release(self) -> None:
        """Send every acknowledgement whose followers all have it, or whose deadline passed."""
        now = time.monotonic()
        keep = []
        for held in self._held:
            behind = [
                f for f in self.followers if self._acked.get(f, {}).get(held.space, 0) < held.seq
            ]
            if behind and now < held.deadline:
                keep.append(held)
                continue
            if behind:
                log.warning(
                    "follower(s) %s did not confirm %s#%d in time", behind, held.space, held.seq
                )
            held.query.reply(held.reply_key, held.payload)
            held.query.drop()
        self._held = keep

    def wait_time(self) -> float | None:
        """Return how long the worker may sleep before a deadline, or None."""
        if not self._held:
            return None
        return max(0.0, min(h.deadline for h in self._held) - time.monotonic())
