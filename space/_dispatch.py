"""The dispatcher: one `TripleSpace`'s changes handed from Zenoh's callbacks to its subscriptions.

Zenoh callbacks only enqueue payloads; the dispatcher takes them in order, on a
thread of its own or on the owner's (`own_thread=False`, `deliver`), lets each
`Subscription` order and filter them, fetches what was missed from the store's
log, and calls the user's callbacks (see `space._subscription`).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import zenoh

from space._subscription import LATEST, Change, Fetch, Subscription
from space.errors import MalformedPayload

log = logging.getLogger("tspace.subscription")

_BATCH = 1000  # queued items handled before their changes are delivered
# A changeset cut into many parts arrives over a few ms, a part at a time: a subscriber
# that delivered each handful as it came would make its agent act (tick) a dozen times
# on one change. While a subscription waits for the end of such a changeset (`waiting`,
# see `space._scoped`), delivery waits. An end is lost only with a link or a store,
# and their return (`catch_up`) ends the wait; as a last resort, delivery goes on when
# no item came for IDLE (a loaded store pauses 20-60 ms between parts), HOLD_MAX in all.
IDLE = 0.2
HOLD_MAX = 1.0


@dataclass(frozen=True)
class _Behind:
    """A queued marker: the store is at `seq`; fetch what is missing up to it."""

    seq: int


class Dispatcher:
    """Delivers changes to every subscription of one `TripleSpace`, on a thread of its own.

    Or, with `own_thread=False`, on the thread that calls `deliver`.
    """

    def __init__(self, fetch_log: Fetch, *, own_thread: bool = True) -> None:
        self._fetch_log = fetch_log
        self._queue: queue.SimpleQueue[tuple[Subscription | None, object] | None] = (
            queue.SimpleQueue()
        )
        self._subs: set[Subscription] = set()
        self._thread = threading.Thread(target=self._run, name="tspace-dispatch", daemon=True)
        self._started = not own_thread  # a caller's thread delivers: none to start
        self._lock = threading.Lock()
        self._out: list[tuple[Subscription | None, object]] = []  # to deliver, in order
        self._held = 0.0  # when delivery started waiting for more parts
        self._last = 0.0  # when the last item came, while delivery waits

    def feed(self, sub: Subscription) -> Callable[[zenoh.Sample], None]:
        """Return the Zenoh callback that feeds a subscription (it only enqueues).

        Zenoh runs it on a Python thread of its own per subscriber. Not on its
        receiving thread (`indirect=False`): taking the GIL from there cost 27 us
        a sample instead of 5 (a changeset in 200 parts, 200 samples).
        """

        def callback(sample: zenoh.Sample) -> None:
            item = sub.item(sample)
            if item is not None:
                self._queue.put((sub, item))

        return callback

    def add(self, sub: Subscription) -> None:
        """Register a subscription, starting the thread on first use."""
        with self._lock:
            self._subs.add(sub)
            if not self._started:
                self._started = True
                self._thread.start()

    def mark_ready(self, sub: Subscription, seq: int, initial: Change | None = None) -> None:
        """Tell the thread that `sub` has seen everything up to `seq`.

        `initial` (the snapshot, if asked for) is delivered before any later change.
        """
        sub.last_seq = seq
        sub.initial = initial
        self._queue.put((sub, None))

    def catch_up(self, seq: int = LATEST) -> None:
        """Make every subscription fetch what it missed up to `seq` from the store's log.

        Called on a reconnection, when the leading store's token comes back, and
        on the store's heartbeat (its current sequence number), so a change missed
        during a cut arrives even when no later change follows it. Safe in a Zenoh
        callback: it only enqueues.
        """
        with self._lock:
            subs = list(self._subs)
        for sub in subs:
            self._queue.put((sub, _Behind(seq)))

    def forget(self, sub: Subscription) -> None:
        """Stop delivering to a subscription."""
        with self._lock:
            self._subs.discard(sub)

    def post(self, work: Callable[[], None]) -> None:
        """Run `work` on the delivering thread, after the changes queued before it; any thread."""
        self._queue.put((None, work))

    def close(self) -> None:
        """Stop the thread after what is queued (`deliver` then returns False)."""
        self._queue.put(None)
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout=5)

    def _run(self) -> None:
        while self.deliver(None):
            pass

    def deliver(self, timeout: float | None) -> bool:
        """Handle what is queued, waiting up to `timeout` s (None: for ever) for a first item,
        and call the callbacks of the changes it makes (unless they wait for more parts).

        Called in a loop by the dispatcher's thread, or by the owner's (`own_thread=False`).
        Returns False once closed.
        """
        held, wait = self._held, timeout
        if held:  # waiting for more parts: delivered once none came for IDLE
            left = IDLE - (time.monotonic() - self._last)
            wait = max(0.0, left if timeout is None else min(left, timeout))
        try:
            batch = [self._queue.get(timeout=wait)]
        except queue.Empty:
            if not held or time.monotonic() - self._last < IDLE:
                return True  # nothing came yet
            batch = []  # nothing came for IDLE, not even the end awaited: deliver
        while batch and len(batch) < _BATCH:  # what is queued already is handled, delivered
            try:
                batch.append(self._queue.get_nowait())
            except queue.Empty:
                break
        out = self._out
        for item in batch:
            if item is None:
                self._deliver(out)
                return False
            self._step(*item, out)
        now = time.monotonic()
        if batch and _waiting(out) and now - (held or now) < HOLD_MAX:
            self._held, self._last = held or now, now
            return True
        self._deliver(out)
        self._held = 0.0
        return True

    def _step(self, sub: Subscription | None, payload: object, out: list) -> None:
        if sub is None:  # work posted
            out.append((None, payload))
            return
        with self._lock:
            alive = sub in self._subs
        if not alive:
            return
        if payload is None:
            sub.ready = True
            if sub.initial is not None:
                out.append((sub, sub.initial))
                sub.initial = None
            early, sub.early = sub.early, []
            for entry in early:
                self._process(sub, entry, out)
        elif isinstance(payload, _Behind):
            if sub.ready:
                self._add(out, sub, sub.behind(payload.seq, self._fetch_log))
        elif not sub.ready:
            sub.early.append(payload)
        else:
            self._process(sub, payload, out)

    def _process(self, sub: Subscription, item: object, out: list) -> None:
        try:
            changes = sub.receive(item, self._fetch_log)
        except MalformedPayload as exc:
            log.warning("malformed change skipped: %s", exc)
            return
        self._add(out, sub, changes)

    @staticmethod
    def _add(out: list[tuple[Subscription, object]], sub: Subscription, items: list) -> None:
        """Queue changes for delivery; parts of one changeset arriving together become one."""
        for item in items:
            if not (out and out[-1][0] is sub and sub.merge(out[-1][1], item)):
                out.append((sub, item))

    def _deliver(self, out: list[tuple[Subscription | None, object]]) -> None:
        for sub in {sub for sub, _item in out if sub is not None}:
            sub.delivered()
        for sub, item in out:
            if sub is None:
                _run_work(item)  # type: ignore[arg-type]
                continue
            with self._lock:
                alive = sub in self._subs
            if not alive:
                continue
            change = sub.change(item)
            if change is None:
                continue
            try:
                sub.callback(change)
            except Exception:  # a user's callback must not stop delivery to the others
                log.exception("subscription callback failed on change %s", change.id)
        out.clear()


def _waiting(out: list[tuple[Subscription | None, object]]) -> bool:
    """Return whether a subscription with changes to deliver waits for more of their parts."""
    return any(sub.waiting for sub in {sub for sub, _item in out if sub is not None})


def _run_work(work: Callable[[], None]) -> None:
    try:
        work()
    except Exception:  # the poster's work must not stop delivery
        log.exception("work posted to the dispatcher failed")
