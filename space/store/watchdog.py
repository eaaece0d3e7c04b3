"""Say so in the log when the store's writer thread stops coming back, and where it is.

The writer thread is the only one that commits and answers writes: when it is
blocked (a Zenoh put that cannot go out, a database call that does not return),
every writer waits and nothing else tells why. The writer beats once per turn
(idle turns come every HEARTBEAT); a daemon thread that sees no beat for
`after` seconds logs a warning with the thread's stack, once per stall, and
logs again when it comes back.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
import traceback

log = logging.getLogger("tspace.store")

AFTER = 10.0  # seconds without a turn before the warning


class Watchdog:
    """Watch one thread's turns; `beat()` from it, `close()` from anyone."""

    def __init__(self, thread: threading.Thread, what: str, after: float = AFTER) -> None:
        self.thread = thread
        self.what = what
        self.after = after
        self._last = time.monotonic()
        self._stop = threading.Event()
        self._watcher = threading.Thread(target=self._watch, name="tspace-watchdog", daemon=True)

    def start(self) -> None:
        """Start watching (the watched thread should beat from now on)."""
        self._last = time.monotonic()
        self._watcher.start()

    def beat(self) -> None:
        """Record a turn of the watched thread."""
        self._last = time.monotonic()

    def close(self) -> None:
        """Stop watching."""
        self._stop.set()
        if self._watcher.is_alive():
            self._watcher.join()

    def _watch(self) -> None:
        stalled_since: float | None = None
        while not self._stop.wait(min(1.0, self.after / 4)):
            last = self._last
            idle = time.monotonic() - last
            if stalled_since is None and idle >= self.after and self.thread.is_alive():
                stalled_since = last
                log.warning(
                    "%s has not finished a turn for %.1f s; it is at:\n%s",
                    self.what,
                    idle,
                    self._stack(),
                )
            elif stalled_since is not None and last != stalled_since:
                log.warning("%s went on after %.1f s", self.what, last - stalled_since)
                stalled_since = None

    def _stack(self) -> str:
        frame = sys._current_frames().get(self.thread.ident or -1)
        return "".join(traceback.format_stack(frame)) if frame is not None else "(no frame)"
