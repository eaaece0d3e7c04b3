"""Run RocksDB's flushes and compactions at a lower CPU priority than the store's writer.

A flush of the memory tables runs 130-450 ms on RocksDB's own threads
(`rocksdb:high` flushes, `rocksdb:low` compacts). At 2,000 changesets/s
on 2 cores the store, the reasoner and the fleet already use ~1.7 of them: each
flush, every 1.5 s, squeezed the writer and the reasoner onto what was left,
and answers queued behind it for 40-90 ms (`bench/fleet.py`'s plot: a spike
at every flush). At nice 10 the kernel gives those threads the cores when the
latency-bound threads do not need them, as RocksDB's own
`Env::LowerThreadPoolCPUPriority` would (pyoxigraph does not expose it). The
work is the same and still done: a commit never waits for a flush.

Linux only (threads found in `/proc/self/task` by the name RocksDB gives
them); elsewhere, nothing changes.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

log = logging.getLogger("tspace.store")

NICE = 10  # RocksDB's background threads' nice value (the store's own threads stay at 0)
_TASKS = Path("/proc/self/task")


def lower_background_threads() -> int:
    """Set RocksDB's background threads in this process to nice `NICE`; return how many.

    Cheap (a few dozen small reads): called after each flush, so threads RocksDB
    starts later are lowered too.
    """
    lowered = 0
    try:
        tasks = list(_TASKS.iterdir())
    except OSError:
        return 0
    for task in tasks:
        try:
            if not (task / "comm").read_text().startswith("rocksdb:"):
                continue
            tid = int(task.name)
            if os.getpriority(os.PRIO_PROCESS, tid) < NICE:
                os.setpriority(os.PRIO_PROCESS, tid, NICE)
            lowered += 1
        except (OSError, ValueError) as exc:  # a thread that ended meanwhile
            log.debug("RocksDB thread %s left as it is: %s", task.name, exc)
    return lowered
