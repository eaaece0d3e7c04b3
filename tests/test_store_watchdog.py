"""A store whose writer thread is stuck says so in its log, with where it is stuck."""

from __future__ import annotations

import logging
import re
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from conftest import wait_for
from space.store.watchdog import Watchdog

WHAT = "the store's tspace-store thread"


@contextmanager
def _watched(
    work: Callable[[Watchdog], None], done: threading.Event, after: float
) -> Iterator[None]:
    """Run `work(watchdog)` on a thread watched after `after` s; on exit set `done` and join."""
    thread = threading.Thread(target=lambda: work(watchdog))
    watchdog = Watchdog(thread, WHAT, after=after)
    thread.start()
    watchdog.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
        watchdog.close()


def _blocked_in_a_put(release: threading.Event, watchdog: Watchdog) -> None:
    watchdog.beat()
    release.wait()
    watchdog.beat()


def test_a_stuck_writer_thread_is_logged_with_its_stack_then_its_return(caplog):
    caplog.set_level(logging.WARNING, logger="tspace.store")
    release = threading.Event()
    with _watched(lambda w: _blocked_in_a_put(release, w), release, after=0.3):
        wait_for(lambda: "has not finished a turn" in caplog.text, 5, "the stall warning")
        warning = caplog.text
        assert re.search(rf"{WHAT} has not finished a turn for \d+\.\d s", warning)
        assert "_blocked_in_a_put" in warning and "release.wait()" in warning
        time.sleep(0.6)
        assert caplog.text.count("has not finished a turn") == 1, "warned once per stall"
        release.set()
        wait_for(lambda: "went on after" in caplog.text, 5, "the return")


def test_a_thread_that_turns_is_never_reported(caplog):
    caplog.set_level(logging.WARNING, logger="tspace.store")
    stop = threading.Event()

    def turning(watchdog: Watchdog) -> None:
        while not stop.wait(0.05):
            watchdog.beat()

    with _watched(turning, stop, after=1.0):  # beats every 0.05 s: a 1 s margin for a busy host
        time.sleep(2.0)
    assert "has not finished a turn" not in caplog.text
