"""A store that cannot commit refuses writes, never serves what is not on disk, and resumes.

The data directory is a small tmpfs of its own (root only: `mount`), filled up
or mounted read-only under the running store.
"""

from __future__ import annotations

import os
import signal
import subprocess
import uuid
from collections.abc import Iterator
from pathlib import Path

import msgpack
import pytest
import zenoh
from rdflib import Literal, Namespace

from conftest import AC_NS, Server, newer_format_dir, serve_refusal, wait_for
from space import ChangesetRejected, SpaceError, TripleSpace

AC = Namespace(AC_NS)

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="mounting a tmpfs needs root")


@pytest.fixture
def disk(tmp_path: Path) -> Iterator[Path]:
    mount = tmp_path / "disk"
    mount.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=24m", "tmpfs", str(mount)], check=True)
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def _fill(path: Path) -> None:
    with open(path, "wb") as f:
        try:
            while True:
                f.write(b"\0" * 65536)
                f.flush()
        except OSError:
            pass  # full: that is the point


def _writes(ts: TripleSpace, i: int) -> bool:
    try:
        ts.write([(AC.after, AC.n, Literal(i))], timeout=5)
        return True
    except ChangesetRejected:
        return False


def test_a_full_disk_refuses_writes_keeps_reads_and_resumes_once_freed(disk: Path):
    srv = Server(disk / "data")
    srv.log = disk.parent / "serve.log"
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="full") as ts:
            ts.write([(AC.before, AC.n, Literal(i)) for i in range(10)])
            _fill(disk / "filler")
            big = [(AC.big, AC.n, Literal(f"{i}" + "x" * 8000)) for i in range(1500)]
            with pytest.raises(ChangesetRejected, match=r"not applied.*(space|No space)"):
                ts.write(big, timeout=30)
            with pytest.raises(ChangesetRejected, match="refuses writes"):
                ts.write([(AC.small, AC.n, Literal(1))])
            # what is on disk is still served, and nothing of the refused writes
            assert len(ts.query((AC.before, None, None))) == 10
            assert len(ts.query((AC.big, None, None))) == 0
            assert len(ts.query((AC.small, None, None))) == 0
            (disk / "filler").unlink()
            wait_for(lambda: _writes(ts, 1), 20, "writes to be accepted again")
            seq = ts.snapshot()[1]
        srv.stop(signal.SIGKILL)
        srv.start()
        with TripleSpace.open(srv.endpoint, space="full") as ts:
            assert ts.snapshot()[1] == seq
            assert len(ts.query((AC.big, None, None))) == 0
    finally:
        srv.stop()


def test_a_read_only_data_directory_serves_reads_refuses_writes_then_resumes(disk: Path):
    srv = Server(disk / "data")
    srv.log = disk.parent / "serve.log"
    srv.start()
    with TripleSpace.open(srv.endpoint, space="ro") as ts:
        ts.write([(AC.kept, AC.n, Literal(1))])
    srv.stop()
    subprocess.run(["mount", "-o", "remount,ro", str(disk)], check=True)
    srv.start()
    try:
        with TripleSpace.open(srv.endpoint, space="ro") as ts:
            assert len(ts.query((AC.kept, None, None))) == 1
            with pytest.raises(ChangesetRejected, match="read-only"):
                ts.write([(AC.lost, AC.n, Literal(1))])
            subprocess.run(["mount", "-o", "remount,rw", str(disk)], check=True)
            wait_for(lambda: _writes(ts, 2), 20, "writes to be accepted again")
            assert len(ts.query((AC.kept, None, None))) == 1
    except SpaceError:
        raise
    finally:
        srv.stop()


def test_a_read_only_directory_of_a_newer_format_is_refused_too(disk: Path):
    """Opened read-only (nothing could be rewritten), a newer format is still not served as
    this one: its log and state would be misread."""
    data = disk / "data"
    newer_format_dir(data)
    subprocess.run(["mount", "-o", "remount,ro", str(disk)], check=True)
    assert "format 99" in serve_refusal(data)


def test_a_triple_a_failed_fsync_left_on_disk_still_ends_with_its_lifespan(disk: Path):
    # With --fsync a commit can reach the database and fail only at its flush (a full
    # disk): the store must not trust what it remembers of its latest commits then
    # (space/store/values.py), or the leases it reads back take the triple for absent
    # and it never expires.
    srv = Server(disk / "data", "--fsync")
    srv.log = disk.parent / "serve.log"
    srv.start()
    t = (AC.lamp, AC.state, AC.on)
    try:
        with TripleSpace.open(srv.endpoint, space="fsync") as ts:
            ts.write([t], lifespan=60)
            ts.remove([t])  # remembered as absent
            _fill(disk / "filler")
            with pytest.raises(ChangesetRejected, match="applied"):  # or "not applied"
                ts.write([t], lifespan=2)
            (disk / "filler").unlink()
            wait_for(lambda: _writes(ts, 1), 20, "writes to be accepted again")
            # whether or not the failed commit's update reached the database
            wait_for(lambda: not ts.query(t), 20, "the triple to end with its lifespan")
    finally:
        srv.stop()


def test_a_write_whose_flush_failed_is_told_what_became_of_it_and_a_retry_too(disk: Path):
    # With --fsync a full disk fails a commit either before its update (nothing written:
    # "not applied") or after it, at its flush (the batch is in the database and served:
    # "applied, but not flushed"). Either way the writer is told what the store serves,
    # and a retry of the same request, while writes are refused, is told the same.
    srv = Server(disk / "data", "--fsync")
    srv.log = disk.parent / "serve.log"
    srv.start()
    t = (AC.lamp, AC.state, AC.on)
    key = "tspace/flush/@/write"
    wire = {
        "v": 1,
        "id": uuid.uuid4().hex,
        "add": [[f"<{AC_NS}lamp>", f"<{AC_NS}state>", f"<{AC_NS}on>"]],
    }

    def send() -> zenoh.Reply:
        return next(iter(ts.session.get(key, payload=msgpack.packb(wire), timeout=5)))

    try:
        with TripleSpace.open(srv.endpoint, space="flush") as ts:
            ts.write([(AC.lamp, AC.n, Literal(0))])
            _fill(disk / "filler")
            first = send()
            assert first.err is not None
            told = first.err.payload.to_string()
            served = bool(ts.query(t))
            assert ("applied, but not flushed" in told) is served, (told, served)
            assert served or "not applied" in told, told
            again = send()
            if served:
                ack = msgpack.unpackb(again.ok.payload.to_bytes())
                assert ack["again"] and ack["id"] == wire["id"], ack
            else:
                assert "not applied" in again.err.payload.to_string()
            (disk / "filler").unlink()
            wait_for(lambda: _writes(ts, 1), 20, "writes to be accepted again")
            assert bool(ts.query(t)) is served
    finally:
        srv.stop()
