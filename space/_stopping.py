"""SIGINT and SIGTERM turned into a call made on a thread of its own, never in the handler.

A Python signal handler runs in the main thread between two bytecodes, maybe while
that thread holds a lock: an `Event.set` or a `Queue.put` made there can wait for
that lock for ever. `tspace serve` so hung on a SIGTERM that came as it entered
`Event.wait` (CI, `tests/test_store_persistence.py::test_sigterm_stops_the_server_cleanly`).
Here Python's handler does nothing: the signal's number reaches a watcher thread
through the wakeup fd, which the interpreter's C handler writes without a lock,
and that thread makes the call.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_END = 0  # the byte that ends the watcher (no signal has number 0)


@contextmanager
def on_stop_signals(action: Callable[[], None]) -> Iterator[None]:
    """Call `action()` on a thread of its own at each SIGINT or SIGTERM within the block.

    Main thread only (Python's rule for signal handlers and the wakeup fd); the
    handlers and wakeup fd before it are put back at its end.
    """
    read, write = os.pipe()
    os.set_blocking(write, False)
    previous = {sig: signal.signal(sig, _noted) for sig in STOP_SIGNALS}
    old_fd = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    watcher = threading.Thread(target=_watch, args=(read, action), name="stop-signals", daemon=True)
    watcher.start()
    try:
        yield
    finally:
        signal.set_wakeup_fd(old_fd)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        os.write(write, bytes([_END]))
        watcher.join(timeout=5)
        os.close(read)
        os.close(write)


def _noted(signum: int, frame: FrameType | None) -> None:
    """Python's handler: nothing to do here, the wakeup fd carries the signal."""


def _watch(fd: int, action: Callable[[], None]) -> None:
    """Call `action` for each stop signal read from the wakeup fd, until the end byte."""
    while True:
        for number in os.read(fd, 64):
            if number == _END:
                return
            if number in STOP_SIGNALS:
                action()
