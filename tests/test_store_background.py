"""The store's RocksDB background threads yield the cores to its writer (`space.store.background`).

Against a real `tspace serve` process: its flushes and compactions run at a lower
CPU priority than the threads that answer writes, before and after a flush.
"""

import os
import time
from pathlib import Path

import pytest
from rdflib import Literal, Namespace

from conftest import AC_NS, Server, wait_for
from space import TripleSpace
from space.store.background import NICE
from space.store.flusher import PAUSE, SMALL

AC = Namespace(AC_NS)

pytestmark = pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="Linux only")


def _threads(pid: int) -> dict[int, tuple[str, int]]:
    """Return each thread of a process: its id -> its name and nice value."""
    threads = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            tid = int(task.name)
            name = (task / "comm").read_text().strip()
            threads[tid] = (name, os.getpriority(os.PRIO_PROCESS, tid))
        except (OSError, ValueError):
            continue  # ended meanwhile
    return threads


def test_rocksdb_threads_run_below_the_stores_own_after_a_flush(tmp_path):
    srv = Server(tmp_path / "data")
    srv.start()
    try:
        assert srv.proc is not None
        pid = srv.proc.pid
        tables = set((tmp_path / "data").rglob("*.sst"))
        with TripleSpace.open(srv.endpoint, space="bg", agent="test") as ts:
            time.sleep(PAUSE)  # the flusher's pause since the start, then enough for a flush
            ts.write([(AC[f"s{i}"], AC.v, Literal(i)) for i in range(SMALL + 10)])
            wait_for(lambda: set((tmp_path / "data").rglob("*.sst")) - tables, what="a flush")
            threads = _threads(pid)
        rocksdb = [nice for name, nice in threads.values() if name.startswith("rocksdb:")]
        assert rocksdb, f"no RocksDB thread in {sorted(threads.values())}"
        assert set(rocksdb) == {NICE}, threads
        others = [(n, nice) for n, nice in threads.values() if not n.startswith("rocksdb:")]
        assert threads[pid][1] == 0 and {nice for _, nice in others} == {0}, others  # writer, Zenoh
    finally:
        srv.stop()
