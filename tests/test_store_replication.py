"""Two stores hold the same space: killing one loses nothing; a returning one catches up."""

import signal

from rdflib import Literal, Namespace

from conftest import AC_NS, Server, store_answers, wait_for
from space import SpaceUnavailable, TripleSpace

AC = Namespace(AC_NS)


def _counted(ts: TripleSpace) -> set[int]:
    return {int(o) for o in ts.query((AC.counter, AC.n, None)).objects()}


def opened(endpoint: str) -> TripleSpace | None:
    """Return a client of the router at `endpoint`, None while it does not listen yet."""
    try:
        return TripleSpace.open(endpoint, space="rep")
    except SpaceUnavailable:
        return None


def leader_and_follower(tmp_path, *leader_args: str) -> tuple[Server, Server]:
    """Start a leading store, and a second one that follows it."""
    a = Server(tmp_path / "a", *leader_args)
    a.start()
    b = Server(tmp_path / "b", "--connect", a.endpoint)
    b.start()
    wait_for(lambda: "follows" in b.logs(), 10, "the second store to follow the first")
    return a, b


def test_killing_the_leader_loses_no_acknowledged_change(tmp_path):
    a, b = leader_and_follower(tmp_path)
    try:
        with TripleSpace.open(b.endpoint, space="rep") as ts:
            for i in range(50):
                ts.write([(AC.counter, AC.n, Literal(i))])
            a.stop(signal.SIGKILL)
            # the follower takes over; a write made right away waits for it
            ts.write([(AC.counter, AC.n, Literal(50))], timeout=20)
            assert _counted(ts) == set(range(51))
            assert ts.snapshot()[1] == 51

        # the old leader comes back, follows, and catches up before answering
        a.extra = ("--connect", b.endpoint)
        a.start()
        wait_for(lambda: "follows" in a.logs(), 10, "the returning store to follow")
        with TripleSpace.open(b.endpoint, space="rep") as ts:
            for i in range(51, 60):
                ts.write([(AC.counter, AC.n, Literal(i))])
        b.stop(signal.SIGKILL)
        wait_for(lambda: store_answers(a.endpoint), 20, "the returning store to take over")
        with TripleSpace.open(a.endpoint, space="rep") as ts:
            assert _counted(ts) == set(range(60))
            assert ts.snapshot()[1] == 60
    finally:
        b.stop()
        a.stop()


def test_subscriber_keeps_its_order_across_a_failover(tmp_path):
    a, b = leader_and_follower(tmp_path)
    try:
        seen = []
        with TripleSpace.open(b.endpoint, space="rep") as ts:
            ts.subscribe(None, seen.append)
            for i in range(5):
                ts.write([(AC.counter, AC.n, Literal(i))])
            a.stop(signal.SIGKILL)
            for i in range(5, 10):
                ts.write([(AC.counter, AC.n, Literal(i))], timeout=20)
            wait_for(lambda: len(seen) >= 10, 10, "every change")
            assert [c.seq for c in seen] == list(range(1, 11))
    finally:
        b.stop()
        a.stop()


def test_a_store_away_longer_than_the_log_copies_the_space_whole(tmp_path):
    a, b = leader_and_follower(tmp_path, "--log-keep", "10")
    try:
        with TripleSpace.open(a.endpoint, space="rep") as ts:
            ts.write([(AC.counter, AC.n, Literal(0))])
            b.stop(signal.SIGKILL)
            # The leader trims its log every 1,000 changesets, to the last 10.
            for i in range(1, 1100):
                ts.write_nowait([(AC.counter, AC.n, Literal(i))])
            ts.write([(AC.counter, AC.n, Literal(1100))], timeout=30)
        b.start()
        wait_for(lambda: "copied whole" in b.logs(), 20, "the returning store to copy the space")
        a.stop(signal.SIGKILL)
        wait_for(lambda: store_answers(b.endpoint), 20, "the returning store to take over")
        with TripleSpace.open(b.endpoint, space="rep") as ts:
            assert _counted(ts) == set(range(1101))
            assert ts.write([(AC.counter, AC.n, Literal(1101))]) and ts.snapshot()[1] == 1102
    finally:
        b.stop()
        a.stop()


def test_a_store_that_led_alone_gives_up_its_own_changes_for_the_leaders(tmp_path):
    """As after a network split that left both stores leading: one history wins, whole."""
    a = Server(tmp_path / "a")
    b = Server(tmp_path / "b")
    try:
        for server, numbers in ((a, range(3)), (b, range(100, 105))):
            server.start()
            with TripleSpace.open(server.endpoint, space="rep") as ts:
                for i in numbers:
                    ts.write([(AC.counter, AC.n, Literal(i))])
            server.stop()
        a.start()
        b.extra = ("--connect", a.endpoint)
        b.start()
        wait_for(lambda: "copied whole" in b.logs(), 20, "the diverged store to copy the space")
        a.stop(signal.SIGKILL)
        wait_for(lambda: store_answers(b.endpoint), 20, "the follower to take over")
        with TripleSpace.open(b.endpoint, space="rep") as ts:
            assert _counted(ts) == {0, 1, 2}
            ts.write([(AC.counter, AC.n, Literal(3))])
            assert ts.snapshot()[1] == 4
    finally:
        b.stop()
        a.stop()


def test_a_store_that_cannot_catch_up_stays_silent_and_never_takes_over(tmp_path):
    """A returning store sees a leader whose log it cannot reach: it must not pass for a copy."""
    a, b = leader_and_follower(tmp_path)
    router = Server(tmp_path / "router", "--no-store")
    try:
        with TripleSpace.open(a.endpoint, space="rep") as ts:
            ts.write([(AC.counter, AC.n, Literal(0))])
            b.stop()
            for i in range(1, 10):  # b misses these
                ts.write([(AC.counter, AC.n, Literal(i))])
        a.stop(signal.SIGKILL)

        # b comes back to a router where a leader is announced but nothing answers for it.
        router.start(wait=False)
        with wait_for(lambda: opened(router.endpoint), 20, "the router") as watcher:
            live = watcher.session.liveliness()
            fake = live.declare_token("tspace/@leader/0")
            since = len(b.logs())
            b.extra = ("--connect", router.endpoint)
            b.start(wait=False)
            asked = "could not ask the leader for its spaces"
            wait_for(lambda: asked in b.logs()[since:], 30, "b to try to catch up")
            assert not list(live.get("tspace/@stores/*", timeout=1.0)), "b announced itself"

            fake.undeclare()  # its leader is gone: b, behind, must not lead
            decided = ("not taking over", "leads")
            wait_for(lambda: any(x in b.logs()[since:] for x in decided), 10, "b to decide")
            assert "leads" not in b.logs()[since:]
            assert not store_answers(router.endpoint)

            # The real leader is back: b catches up, then announces itself.
            a.extra = ("--connect", router.endpoint)
            a.start()
            wait_for(lambda: "follows" in b.logs()[since:], 30, "b to catch up")
            a.stop(signal.SIGKILL)
        wait_for(lambda: store_answers(b.endpoint), 20, "b to take over")
        with TripleSpace.open(b.endpoint, space="rep") as ts:
            assert _counted(ts) == set(range(10))
            assert ts.snapshot()[1] == 10
    finally:
        for server in (b, a, router):
            if server.proc is not None:
                server.stop()
