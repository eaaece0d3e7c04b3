"""The store's log, one quad a changeset: found by seq and by request id, kept to `log_keep`."""

from __future__ import annotations

from pathlib import Path

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
