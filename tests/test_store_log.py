"""The store's log, one quad a changeset: found by seq and by request id, kept to `log_keep`."""

from __future__ import annotations

from pathlib import Path

from conftest import wait_for
from space.store.db import COMPACT_EVERY, StoreDB
from space.store.db_layout import Entry


def _entry(seq: int) -> Entry:
    s, p = "<http://ex.org/robot>", "<http://ex.org/level>"
    entry = Entry(space="log", seq=seq, request=f"req {seq}/x", payload=b"cs%d" % seq)
    entry.plain = [[s, p, f'"{seq}"']]
    if seq % 2:
        entry.dropped = b"why %d" % seq
    return entry


def test_the_log_keeps_the_latest_entries_each_found_by_seq_and_by_request_id(tmp_path: Path):
    keep = 10
    db = StoreDB(tmp_path, log_keep=keep)
    try:
        last = COMPACT_EVERY + 5
        for seq in range(1, last + 1):
            db.commit([_entry(seq)])
        compacted = COMPACT_EVERY - keep  # at the COMPACT_EVERY-th commit
        kept = db.log("log", 1, last)
        assert [seq for seq, _ in kept] == list(range(compacted + 1, last + 1))
        assert all(payload == b"cs%d" % seq for seq, payload in kept)
        assert db.outcome("log", f"req {last}/x") == (last, b"cs%d" % last, b"why %d" % last)
        assert db.outcome("log", f"req {last - 1}/x") == (last - 1, b"cs%d" % (last - 1), b"")
        assert db.outcome("log", f"req {compacted}/x") is None  # gone with its entry
        assert db.outcome("log", "never sent") is None
    finally:
        db.close()


def test_compactions_after_a_restart_keep_exactly_the_latest_entries(tmp_path: Path):
    """The first compaction of a process finds the old entries by reading the log, the next
    ones name the entries since the last cut: each leaves exactly the `log_keep` latest."""
    keep, seq = 10, 0
    # a restart between: the last cut is not remembered across it
    for commits, cut in ((COMPACT_EVERY + 5, COMPACT_EVERY - keep), (2 * COMPACT_EVERY, None)):
        db = StoreDB(tmp_path, log_keep=keep)
        try:
            for _ in range(commits):
                seq += 1
                db.commit([_entry(seq)])
                if seq == 2 * COMPACT_EVERY + 5:  # the first compaction after the restart
                    assert db.outcome("log", f"req {seq - keep}/x") is None
            cut = cut or seq - keep  # the second one after it: the seq of its last commit
            assert [n for n, _ in db.log("log", 1, seq)] == list(range(cut + 1, seq + 1))
            assert db.outcome("log", f"req {cut}/x") is None
            first = _entry(cut + 1)
            assert db.outcome("log", first.request) == (cut + 1, first.payload, first.dropped)
        finally:
            db.close()


def test_a_retry_is_told_its_first_outcome_whenever_the_store_first_read_its_log(
    tmp_path: Path,
):
    """Request ids are known from memory (`request_ids`): those committed after the log was
    read are found, those cut with their entries are not, and a restart reads them again."""
    db = StoreDB(tmp_path, log_keep=10)
    try:
        assert db.outcome("log", "req 1/x") is None  # the log is read from here, empty
        for seq in range(1, COMPACT_EVERY + 1):
            db.commit([_entry(seq)])
            if seq == 1:
                assert db.outcome("log", "req 1/x") == (1, b"cs1", b"why 1")
                _known(db)
        assert db.outcome("log", "req 1/x") is None  # cut with its entry
        assert db.outcome("log", f"req {COMPACT_EVERY - 9}/x") is not None
    finally:
        db.close()
    db = StoreDB(tmp_path, log_keep=10)
    try:
        last = COMPACT_EVERY
        assert db.outcome("log", f"req {last}/x") == (last, b"cs%d" % last, b"")  # looked up
        _known(db)
        assert db.outcome("log", f"req {last}/x") == (last, b"cs%d" % last, b"")
        assert db.outcome("log", f"req {last - 10}/x") is None
    finally:
        db.close()


def _known(db: StoreDB) -> None:
    """Wait until the store knows the log's ids from memory (read on a thread of their own)."""
    wait_for(lambda: db.requests.known("log"), 10, "the log's request ids read")
