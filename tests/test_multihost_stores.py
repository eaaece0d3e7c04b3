"""Two stores on two hosts hold one space: losing a store's host loses nothing.

Hosts `s1` and `s2` each run `tspace serve` with a store (s2's follows s1's),
`w` a router without a store, through which the test writes. A host's loss is
its cable pulled and every process killed, with no goodbye: the other store
learns of it from Zenoh's lease (10 s, deploy/multihost/router.json5).
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from netns import Host, Network, Proc, require_netns
from rdflib import Literal, Namespace

from conftest import AC_NS, wait_for
from space import SpaceError, TripleSpace

pytestmark = pytest.mark.netns

AC = Namespace(AC_NS)
SPACE = "replicated"


@pytest.fixture
def net(tmp_path: pytest.TempPathFactory) -> Iterator[Network]:
    require_netns()
    with Network(["s1", "s2", "w"], tmp_path) as network:  # type: ignore[arg-type]
        yield network


def lose(host: Host) -> None:
    """Lose a host as in a power failure, keeping its disk: cable pulled, processes killed."""
    host.cut()
    host.kill_all()


def wait_following(proc: Proc, since: int = 0) -> None:
    wait_for(
        lambda: "follows" in proc.logs()[since:], 30, f"the store of {proc.host.name} to follow"
    )


def counted(ts: TripleSpace) -> set[int]:
    return {int(o) for o in ts.query((AC.counter, AC.n, None), timeout=10).objects()}


def answers(ts: TripleSpace) -> bool:
    """Return True once a store answers `ts` (within a second)."""
    try:
        ts.snapshot(timeout=1.0)
    except SpaceError:
        return False
    return True


def write(ts: TripleSpace, numbers: range) -> None:
    for i in numbers:
        # Acknowledged: durable at the leader and held by the follower.
        ts.write([(AC.counter, AC.n, Literal(i))], timeout=30)


def test_a_stores_host_lost_and_back_loses_nothing_and_catches_up(net):
    s1, s2, w = net["s1"], net["s2"], net["w"]
    s1.serve()
    follower = s2.serve(connect=[s1])
    wait_following(follower)
    w.serve(store=False, connect=[s1, s2])
    with TripleSpace.open(w.control, space=SPACE) as ts:
        write(ts, range(20))
        lose(s1)
        started = time.monotonic()
        write(ts, range(20, 30))  # waits for s2 to take over, then goes on
        taken_over = time.monotonic() - started
        assert counted(ts) == set(range(30))

        # s1 comes back with its disk and follows s2. Nothing is written from now on until
        # s1 answered: the 10 changes it missed reach it only by its own catch-up.
        s1.restore()
        log = (s1.net.workdir / "s1-serve.log").read_text(errors="replace")
        returned = s1.serve(connect=[s2])
        wait_following(returned, len(log))

        # Now s2's host goes: s1 alone answers, through its own router, with every change.
        lose(s2)
        with TripleSpace.open(s1.control, space=SPACE) as direct:
            wait_for(lambda: answers(direct), 30, "s1 to take over")
            assert counted(direct) == set(range(30))
            assert direct.snapshot(timeout=10)[1] == 30
        write(ts, range(30, 40))
        assert counted(ts) == set(range(40))
        assert ts.snapshot(timeout=10)[1] == 40
    assert taken_over < 25, f"the follower took {taken_over:.1f} s to take over"
