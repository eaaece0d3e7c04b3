"""The store's memory of the request ids its logs hold: never "not logged" for one that is."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

from conftest import wait_for
from space.store import request_ids
from space.store.db_layout import Entry, request_iri
from space.store.request_ids import RequestIds


class Log:
    """A space's log as the database gives it, read when `release` is set."""

    def __init__(self, seqs: range) -> None:
        self.rows = [(seq, request_iri(f"r{seq}")) for seq in seqs]
        self.release = threading.Event()
        self.fail = False
        self.reads = 0

    def load(self, space: str) -> Iterator[tuple[int, str]]:
        self.reads += 1
        snapshot = list(self.rows)  # taken when the read begins, as Oxigraph's
        assert self.release.wait(10)
        if self.fail:
            raise OSError("I/O error")
        yield from snapshot


def _entry(seq: int) -> Entry:
    return Entry(space="s", seq=seq, request=f"r{seq}", payload=b"")


def _known(ids: RequestIds) -> None:
    wait_for(lambda: ids.known("s"), 10, "the log's request ids read")


def test_ids_committed_and_cut_while_the_log_is_read_are_counted():
    log = Log(range(1, 11))
    ids = RequestIds(log.load)
    assert ids.may_hold("s", "r99")  # reading: every id is looked up
    ids.committed([_entry(11), _entry(12)])
    ids.cut("s", 3)
    log.release.set()
    _known(ids)
    assert [ids.may_hold("s", f"r{n}") for n in (3, 4, 10, 11, 12)] == [
        False,
        True,
        True,
        True,
        True,
    ]
    assert not ids.may_hold("s", "r13")
    ids.committed([_entry(13)])
    ids.cut("s", 11)
    assert [ids.may_hold("s", f"r{n}") for n in (11, 12, 13)] == [False, True, True]


def test_a_failed_read_of_the_log_is_tried_again(monkeypatch):
    monkeypatch.setattr(request_ids, "RETRY", 0.05)
    log = Log(range(1, 4))
    log.fail = True
    log.release.set()
    ids = RequestIds(log.load)
    ids.may_hold("s", "r1")
    wait_for(lambda: log.reads >= 1, 10, "the log read")
    time.sleep(0.1)
    assert not ids.known("s")  # failed: looked up
    ids.committed([_entry(4)])
    log.fail = False
    log.rows.append((4, request_iri("r4")))
    _known(ids)
    assert log.reads >= 2
    assert ids.may_hold("s", "r4") and ids.may_hold("s", "r1")
    assert not ids.may_hold("s", "r5")


def test_beyond_the_limit_a_space_goes_back_to_lookups(monkeypatch):
    monkeypatch.setattr(request_ids, "LIMIT", 5)
    log = Log(range(1, 4))
    log.release.set()
    ids = RequestIds(log.load)
    _known(ids)
    ids.committed([_entry(4), _entry(5)])
    assert not ids.may_hold("s", "r6")
    ids.committed([_entry(6)])  # 6 ids: too many
    assert not ids.known("s")
    assert ids.may_hold("s", "r7")  # looked up from now on
    ids.clear()  # the database reopened: read again
    _known(ids)


@pytest.fixture(autouse=True)
def _no_thread_left() -> Iterator[None]:
    yield
    for thread in threading.enumerate():
        if thread.name == "tspace-request-ids":
            thread.join(10)
