"""Flush Oxigraph's memory tables to disk in the background, every so many triples committed.

A commit is durable once it is in RocksDB's write-ahead log; what it wrote stays
in memory tables until they are flushed, and as pyoxigraph opens the database
that happens far too late: a store that loaded 1M triples in changesets of
10,000 held ~800 MB of them (RSS ~1 GB). `Store.flush()` every `EVERY` triples
keeps it near 100 MB and costs no throughput: it is work RocksDB does anyway,
done here on a thread of its own (Oxigraph releases the GIL), beside the writer.

A small memory table also makes each commit cheaper: most of a commit's time is
RocksDB finding where each index entry goes in the table's skip list, and a
table of 50,000 triples' entries no longer fits the caches. A reasoner's answer
replacing 200 values committed 0.6-0.7x as long flushed every 10,000 as every
50,000 (docs/performance.md, "A subject's predicates in one part"). So it also
flushes after `SMALL` triples when the last flush is `PAUSE` old: at most once
a second, so a bulk load (40,000 triples a second) flushes about as often as
before, where flushing every 10,000 cost it 15 % more CPU. RocksDB's threads doing
the flush run at a lower priority than the writer (`space.store.background`).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import pyoxigraph as ox

from space.store.background import lower_background_threads

log = logging.getLogger("tspace.store")

EVERY = 50_000  # triples committed between background flushes
SMALL = 10_000  # or this many, once the last flush is PAUSE old
PAUSE = 1.0  # seconds


class Flusher:
    """Flush a store on a thread of its own once `EVERY` triples were committed (or `SMALL`).

    Args:
        store: returns the store to flush now (the database may reopen it).
    """

    def __init__(self, store: Callable[[], ox.Store | None], every: int = EVERY) -> None:
        self._store = store
        self._every = every
        self._written = 0
        self._last = time.monotonic()  # when the last flush was asked for
        self._wake = threading.Event()
        self._lock = threading.Lock()  # held while flushing, and by `paused`
        self._stop = False
        self._thread = threading.Thread(target=self._run, name="tspace-flush", daemon=True)
        self._thread.start()

    def wrote(self, triples: int) -> None:
        """Count triples committed; wake the flusher once enough are (writer thread)."""
        self._written += triples
        if self._written >= self._every or (
            self._written >= min(SMALL, self._every) and time.monotonic() >= self._last + PAUSE
        ):
            self._written = 0
            self._last = time.monotonic()
            self._wake.set()

    @contextmanager
    def paused(self) -> Iterator[None]:
        """Hold off flushes (while the database is closed or reopened)."""
        with self._lock:
            yield

    def close(self) -> None:
        """Stop the thread (after the flush it may be doing)."""
        self._stop = True
        self._wake.set()
        self._thread.join()

    def _run(self) -> None:
        while True:
            self._wake.wait()
            self._wake.clear()
            if self._stop:
                return
            with self._lock:
                store = self._store()
                if store is None:
                    continue
                try:
                    store.flush()
                except OSError as exc:  # the next commit says it too, and fails the store
                    log.error("could not flush the database: %s", exc)
                lower_background_threads()  # any RocksDB started for this flush too
