"""Run reads beside the writer, each on its own thread, each within a time limit.

Oxigraph releases the GIL while it evaluates, and every call reads its own
snapshot, so a read never holds up the writer. Its `Store.query` cannot be
cancelled, though, so a time limit works in two ways:

- a read that yields results (templates, SELECT, CONSTRUCT) checks its
  deadline between results and stops;
- one that computes for long before its first result (an aggregate over a
  huge join) cannot be stopped: at its deadline its caller gets the time-limit
  error at once (from the timer thread), and the thread runs on until Oxigraph
  returns, then its result is thrown away.

Such a runaway keeps one of `slots` (default 16): at most that many reads run
at once, runaways included, and a read that finds every slot taken is refused
at once with an error naming the cap, rather than queued behind them.
"""

from __future__ import annotations

import heapq
import itertools
import logging
import threading
import time
from collections.abc import Callable

import zenoh

from space.errors import SpaceError
from space.store.queries import Deadline, time_limit_message

log = logging.getLogger("tspace.store")

Job = Callable[[Deadline], bytes | None]


class _Read:
    def __init__(self, query: zenoh.Query, key: str, deadline: Deadline) -> None:
        self.query = query
        self.key = key
        self.deadline = deadline
        self.lock = threading.Lock()
        self.answered = False
        self.expired = False  # still running when its deadline passed

    def answer(self, payload: bytes | None = None, error: str | None = None) -> bool:
        """Reply once (the reader or the timer, whichever comes first); return whether this did."""
        with self.lock:
            if self.answered:
                return False
            self.answered = True
        try:
            if error is not None:
                self.query.reply_err(error.encode())
            elif payload:
                self.query.reply(self.key, payload)
        except zenoh.ZError as exc:  # the requester is gone: nothing to tell
            log.debug("could not answer a read on %s: %s", self.key, exc)
        self.query.drop()
        return True


class Readers:
    """Read threads with a time limit each and a cap on how many run at once.

    `submit` may be called from any thread; `close` waits for nothing (a
    runaway read's thread is a daemon, its result unwanted).
    """

    def __init__(self, *, limit: float = 10.0, slots: int = 16) -> None:
        self.limit = limit
        self.slots = slots
        self._running = 0
        self._past_limit = 0
        self._lock = threading.Lock()
        self._timers: list[tuple[float, int, _Read]] = []
        self._wake = threading.Condition(self._lock)
        self._counter = itertools.count()
        self._closed = False
        self._timer = threading.Thread(target=self._time, name="tspace-read-timer", daemon=True)
        self._timer.start()

    @property
    def running(self) -> int:
        """Return how many reads are running (runaways past their limit included)."""
        return self._running

    def close(self) -> None:
        """Stop the timer thread (reads still running finish unanswered)."""
        with self._wake:
            self._closed = True
            self._wake.notify()
        self._timer.join()

    def submit(self, query: zenoh.Query, key: str, job: Job, limit: float | None = None) -> None:
        """Run `job(deadline)` on a thread and reply with what it returns (None: nothing more).

        `limit` (the request's) is capped by the store's own. A `SpaceError`
        or `ValueError` from the job becomes the error reply.
        """
        limit = min(limit or self.limit, self.limit)
        read = _Read(query, key, Deadline(limit))
        with self._wake:
            if self._running >= self.slots:
                busy = (
                    f"store busy: {self._running} reads running (at most {self.slots}; "
                    f"{self._past_limit} past their time limit), try again"
                )
            else:
                busy = ""
                self._running += 1
                heapq.heappush(self._timers, (read.deadline.at, next(self._counter), read))
                self._wake.notify()
        if busy:
            read.answer(error=busy)
            return
        threading.Thread(target=self._run, args=(read, job), daemon=True).start()

    def _run(self, read: _Read, job: Job) -> None:
        try:
            payload = job(read.deadline)
            read.answer(payload)
        except (SpaceError, ValueError) as exc:
            read.answer(error=str(exc))
        except Exception as exc:  # a bug must not leave the caller waiting; say what it was
            log.exception("read on %s failed", read.key)
            read.answer(error=f"internal error: {type(exc).__name__}: {exc}")
        finally:
            with self._lock:
                self._running -= 1
                if read.expired:
                    self._past_limit -= 1

    def _time(self) -> None:
        """Answer every read still running at its deadline with the time-limit error."""
        with self._wake:
            while not self._closed:
                now = time.monotonic()
                while self._timers and self._timers[0][0] <= now:
                    _at, _n, read = heapq.heappop(self._timers)
                    if not read.answered:
                        read.expired = True
                        self._past_limit += 1
                        threading.Thread(target=self._expire, args=(read,), daemon=True).start()
                wait = self._timers[0][0] - now if self._timers else None
                self._wake.wait(wait)

    def _expire(self, read: _Read) -> None:
        if read.answer(error=time_limit_message(read.deadline.limit)):
            log.warning(
                "a read on %s ran past its %g s limit; its thread runs on until Oxigraph returns",
                read.key,
                read.deadline.limit,
            )
