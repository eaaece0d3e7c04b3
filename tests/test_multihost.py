"""One space over several hosts: routers meshed across network namespaces (`tests/netns.py`).

Host `a` runs `tspace serve` (router + store) and the fleet monitor, `b` a
router with a robot's agents, `c` a router with the reasoners, `d` a router
with a robot that vanishes. Every router is configured as docs/deployment.md
says, every agent is a client of its own host's router, and the test reaches
each host through its router's control socket.
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Iterable, Iterator

import pytest
from agentprocs import knowledge
from netns import REPO, Host, Network, require_netns
from rdflib import BNode, Graph, Literal, Namespace
from rdflib.term import Node

from agents.firings import without_records
from conftest import AC_NS, wait_for
from space import Change, TripleSpace
from space.presence import alive_agents
from space.terms import Triple

pytestmark = pytest.mark.netns

AC = Namespace(AC_NS)
ROBOT_AGENTS = ("hw_monitor", "nav_monitor", "behavior")
RULES = REPO / "rules"

# What robot1's sensors report during the cut: each step changes one value that rules read.
SENSORS: list[tuple[Node, Node, list[Node]]] = [
    (AC.robot1_battery, AC.battery_level, [Literal(x) for x in ("low", "very low", "normal")]),
    (AC.robot1, AC.location, [AC.hall, AC.room_101, AC.corridor, AC.dock1]),
    (AC.robot1_wheels, AC.fault, [Literal("error"), Literal("none")]),
    (AC.robot1_laser, AC.obstacles, [Literal("surrounded"), Literal("clear")]),
    (AC.robot1, AC.interacting_with, [AC.patient_ane, AC.patient_jon]),
]
ANON = BNode("anonymous")
LEASE = 10.0  # seconds: deploy/multihost/router.json5
STEPS = 30
RATE = 10.0  # changesets per second, a robot's sensor rate


@pytest.fixture(scope="module")
def net(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Network]:
    """Four hosts, each with a router; the store on `a`."""
    require_netns()
    with Network(["a", "b", "c", "d"], tmp_path_factory.mktemp("mh")) as network:
        a, b, c, d = network["a"], network["b"], network["c"], network["d"]
        a.serve()
        b.serve(store=False, connect=[a])
        c.serve(store=False, connect=[a, b])
        d.serve(store=False, connect=[a])
        yield network


def new_space(host: Host, graph: Graph | None = None) -> str:
    """Make a space of the test's own holding `graph` (default: the hospital robot)."""
    name = f"mh{uuid.uuid4().hex[:8]}"
    with TripleSpace.open(host.control, space=name) as ts:
        ts.write(knowledge() if graph is None else graph, timeout=10)
    return name


def start_reasoner(host: Host, seen: list[Change], space: str, *args: str) -> None:
    """Start the reasoner of `space` on `host`; return once it answered the space's state."""
    host.agent("reasoner", space=space, args=args)
    wait_for(lambda: any(ch.agent == "reasoner" for ch in seen), 60, "the reasoner's first answer")


def canonical(triples: Iterable[Triple]) -> frozenset[Triple]:
    """Return the triples without firing records, every blank node made the same.

    Each reasoner parses the ontology itself, so the anonymous classes it infers
    memberships of have labels of its own.
    """
    return frozenset(
        tuple(ANON if isinstance(x, BNode) else x for x in t)  # type: ignore[misc]
        for t in without_records(triples)
    )


def answers(seen: list[Change], ids: list[str]) -> dict[int, tuple[frozenset, ...]]:
    """Return the reasoner's conclusions by the index of the changeset they answer."""
    index = {cid: i for i, cid in enumerate(ids)}
    out = {}
    for ch in seen:
        if ch.agent == "reasoner" and ch.cause in index:
            lists = (ch.added, ch.removed, ch.inferred_added, ch.inferred_removed)
            out[index[ch.cause]] = tuple(canonical(x) for x in lists)
    return out


def answered(seen: list[Change], cause: str) -> bool:
    """Return True once the reasoner answered changeset `cause`."""
    return any(ch.agent == "reasoner" and ch.cause == cause for ch in seen)


def state(ts: TripleSpace) -> tuple[frozenset[Triple], frozenset[Triple]]:
    """Return the space's asserted and inferred graphs, canonical."""
    return canonical(ts.match(None, graph="asserted")), canonical(ts.match(None, graph="inferred"))


def play(ts: TripleSpace) -> list[str]:
    """Write the sensors' steps at `RATE`, each replacing the old value; return the ids."""
    current = {(s, p): values[-1] for s, p, values in SENSORS}
    current[AC.robot1, AC.interacting_with] = None
    ids = []
    for step in range(STEPS):
        s, p, values = SENSORS[step % len(SENSORS)]
        new = values[(step // len(SENSORS)) % len(values)]
        old = current[s, p]
        ids.append(ts.apply([(s, p, new)], [(s, p, old)] if old is not None else []))
        current[s, p] = new
        time.sleep(1 / RATE)  # the sensors' pace, not a wait for a condition
    return ids


def test_a_write_on_one_host_is_reasoned_on_another(net):
    a, b, c = net["a"], net["b"], net["c"]
    robot = knowledge()
    robot.remove((AC.robot1_battery, AC.charge_percent, None))  # so that --charge applies
    space = new_space(a, robot)
    seen: list[Change] = []
    with TripleSpace.open(a.control, space=space) as ts:
        ts.subscribe(None, seen.append)
        start_reasoner(c, seen, space)
        b.agent("hw_monitor", space=space, robot="robot1", args=["--charge", "8"])
        for kind in ROBOT_AGENTS[1:]:
            b.agent(kind, space=space, robot="robot1")
        names = {"reasoner", *(f"{kind}.robot1" for kind in ROBOT_AGENTS)}
        wait_for(lambda: names <= set(alive_agents(ts.session, space)), 60, "every agent alive")

        def concluded() -> Change | None:
            going = (AC.robot1, AC.current_task, AC.task_going_to_dock)
            return next((ch for ch in seen if ch.agent == "reasoner" and going in ch.added), None)

        answer = wait_for(concluded, 60, "the reasoner on c sending robot1 to its dock")
        cause = next(ch for ch in seen if ch.id == answer.cause)
        assert cause.agent == "hw_monitor.robot1"
        assert (AC.robot1_battery, AC.battery_level, Literal("very low")) in cause.added
        assert (AC.robot1_base, AC.motion_speed, Literal("low")) in answer.added

        def acted() -> bool:
            target = (AC.robot1, AC.target_place, AC.dock1)
            return any(ch.agent == "behavior.robot1" and target in ch.added for ch in seen)

        wait_for(acted, 30, "robot1's behaviour on b heading for the dock")


def test_a_cut_link_loses_no_change(net):
    a, b, c = net["a"], net["b"], net["c"]
    reference, cut = new_space(a), new_space(a)
    with (
        TripleSpace.open(a.control, space=reference) as ref_ts,
        TripleSpace.open(a.control, space=cut) as cut_ts,
        TripleSpace.open(b.control, space=reference) as ref_writer,
        TripleSpace.open(b.control, space=cut) as cut_writer,
        TripleSpace.open(c.control, space=cut) as cut_watcher,
    ):
        ref_seen: list[Change] = []
        cut_seen: list[Change] = []
        on_c: list[Change] = []
        ref_ts.subscribe(None, ref_seen.append)
        cut_ts.subscribe(None, cut_seen.append)
        start_reasoner(c, ref_seen, reference)
        start_reasoner(c, cut_seen, cut)
        cut_watcher.subscribe(None, on_c.append)

        ref_ids = play(ref_writer)
        wait_for(lambda: answered(ref_seen, ref_ids[-1]), 30, "the reference's last answer")

        with c.outage(5.0):
            cut_ids = play(cut_writer)
            assert not {ch.id for ch in on_c} & set(cut_ids), "c saw changes through a cut link"

        wait_for(lambda: answered(cut_seen, cut_ids[-1]), 30, "the reasoner catching up")
        delivered = [ch.id for ch in on_c if ch.id in set(cut_ids)]
        assert delivered == cut_ids, "c did not get every change written during the cut, in order"
        seqs = [ch.seq for ch in on_c]
        assert seqs == list(range(seqs[0], seqs[0] + len(seqs))), "gap or duplicate on c"
        assert answers(cut_seen, cut_ids) == answers(ref_seen, ref_ids)
        assert state(cut_ts) == state(ref_ts)


def test_a_cut_hosts_latest_sensor_values_arrive_and_are_reasoned_on_after_the_cut(net):
    """The cut host's own writes fail during the cut; its agents re-send their latest state."""
    a, b, c = net["a"], net["b"], net["c"]
    robot = knowledge()
    robot.remove((AC.robot1_battery, AC.charge_percent, None))  # so that --charge applies
    # Away from its dock: sent there (GoingToDock) while on it, it would charge at once and
    # its level leave very low (never a charging battery's), racing the reads at the end.
    robot.set((AC.robot1, AC.location, AC.corridor))
    space = new_space(a, robot)
    seen: list[Change] = []
    arrived: dict[str, float] = {}
    battery = AC.robot1_battery

    def record(change: Change) -> None:
        arrived[change.id] = time.monotonic()
        seen.append(change)

    with TripleSpace.open(a.control, space=space) as ts:
        ts.subscribe(None, record)
        start_reasoner(c, seen, space)
        # 24 % draining about 5.6 % a second: 20, 15, 10, 5 (very low: the dock), then 0,
        # all but the first reading while b's link is cut.
        b.agent(
            "hw_monitor",
            space=space,
            robot="robot1",
            args=["--charge", "24", "--time-scale", "230"],
        )

        def read(percent: int) -> bool:
            t = (battery, AC.charge_percent, Literal(percent))
            return any(ch.agent == "hw_monitor.robot1" and t in ch.added for ch in seen)

        wait_for(lambda: read(20), 60, "robot1's first battery reading")
        with b.outage(5.0):
            cut = time.monotonic()
        restored = time.monotonic()
        from_b = [ch.id for ch in seen if ch.agent == "hw_monitor.robot1"]
        assert not [i for i in from_b if cut < arrived[i] < restored], "a write crossed the cut"

        very_low = (battery, AC.battery_level, Literal("very low"))

        def reasoned() -> Change | None:
            """Return the hw_monitor's very low reading once the reasoner answered it."""
            hw = [ch for ch in seen if ch.agent == "hw_monitor.robot1" and very_low in ch.added]
            going = (AC.robot1, AC.current_task, AC.task_going_to_dock)
            answered = {ch.cause for ch in seen if ch.agent == "reasoner" and going in ch.added}
            return next((ch for ch in hw if ch.id in answered), None)

        reading = wait_for(reasoned, 15, "robot1's very low battery, reasoned on")
        took = time.monotonic() - restored
        assert arrived[reading.id] > restored, "the very low reading crossed the cut link"
        # The latest reading, not one from the cut, is the space's (readings are functional).
        wait_for(lambda: read(0), 10, "robot1's latest battery reading")
        assert set(ts.match((battery, AC.charge_percent, None))) == {
            (battery, AC.charge_percent, Literal(0))
        }
        assert set(ts.match((battery, AC.battery_level, None))) == {very_low}
        assert took < 10, f"the cut host's latest state took {took:.1f} s to be reasoned on"


def fleet_space(host: Host) -> str:
    """Make a space with two hospital robots: robot1 charging on dock 1, Ane waiting for it."""
    fleet = Graph().parse(REPO / "ontology" / "selfconfig.ttl")
    for name in ("common.ttl", "hospital_fleet.ttl"):
        fleet.parse(REPO / "ontology" / "robots" / name)
    robot1 = {
        AC.current_task: AC.task_charging,
        AC.dock: AC.dock1,
        AC.location: AC.dock1,
        AC.position_x: Literal(0.0),
        AC.position_y: Literal(0.0),
        AC.attended_person: AC.patient_ane,  # asked for while charging: it goes after
        AC.resume_task: AC.task_attending_patient,
    }
    for predicate, value in robot1.items():
        fleet.set((AC.robot1, predicate, value))
    fleet.set((AC.dock1, AC.dock_status, Literal("occupied")))
    fleet.set((AC.robot1_battery, AC.charge_percent, Literal(20)))
    fleet.set((AC.robot1_battery, AC.battery_level, Literal("low")))
    return new_space(host, fleet)


def test_a_robot_whose_host_vanishes_is_gone_and_the_fleet_takes_back_its_patient_and_dock(net):
    a, b, c, d = net["a"], net["b"], net["c"], net["d"]
    space = fleet_space(a)
    seen: list[Change] = []
    with TripleSpace.open(a.control, space=space) as ts:
        ts.subscribe(None, seen.append)
        rules = [
            x for name in ("fleet", "presence") for x in ("--rules", str(RULES / f"{name}.rules"))
        ]
        start_reasoner(c, seen, space, *rules)
        a.agent("fleet_monitor", space=space)
        for kind in ROBOT_AGENTS:
            d.agent(kind, space=space, robot="robot1")  # robot1's host: it will vanish
            b.agent(kind, space=space, robot="robot2")
        for robot in (AC.robot1, AC.robot2):
            present = (robot, AC.presence, Literal("present"))
            wait_for(lambda t=present: t in ts.match(t), 60, f"{robot} present")
        attending = (AC.robot1, AC.attended_person, AC.patient_ane)
        assert attending in ts.match(attending)

        d.vanish()
        vanished = time.monotonic()
        robot1_agents = {f"{kind}.robot1" for kind in ROBOT_AGENTS}
        wait_for(
            lambda: not robot1_agents & set(alive_agents(ts.session, space)),
            30,
            "robot1's agents seen gone",
        )
        gone = (AC.robot1, AC.presence, Literal("gone"))

        def marked_gone() -> Change | None:
            return next(
                (ch for ch in seen if ch.agent == "fleet_monitor" and gone in ch.added), None
            )

        mark = wait_for(marked_gone, 10, "the fleet monitor marking robot1 gone")
        assert time.monotonic() - vanished > 5  # the lease, not a goodbye, told the others

        def answer() -> Change | None:
            return next((ch for ch in seen if ch.agent == "reasoner" and ch.cause == mark.id), None)

        reaction = wait_for(answer, 10, "the fleet rules' answer to robot1 gone")
        # Ane goes to robot2, dock 1 is free again: in one answer, caused by the mark.
        assert attending in reaction.removed
        assert (AC.robot2, AC.attended_person, AC.patient_ane) in reaction.added
        assert (AC.robot2, AC.requested_task, AC.task_attending_patient) in reaction.added
        assert (AC.robot1, AC.dock, AC.dock1) in reaction.removed
        assert (AC.dock1, AC.dock_status, Literal("free")) in reaction.added

        def robot2_attends() -> bool:
            task = (AC.robot2, AC.current_task, AC.task_attending_patient)
            return any(ch.agent == "behavior.robot2" and task in ch.added for ch in seen)

        wait_for(robot2_attends, 10, "robot2's behaviour on b taking Ane over")


def test_changes_written_during_a_cut_longer_than_the_lease_arrive(net):
    b, c = net["b"], net["c"]
    space = f"mh{uuid.uuid4().hex[:8]}"
    on_c: list[Change] = []
    with (
        TripleSpace.open(b.control, space=space) as writer,
        TripleSpace.open(c.control, space=space) as watcher,
    ):
        watcher.subscribe(None, on_c.append)
        with c.outage(LEASE + 2):
            ids = [writer.write([(AC.robot1, AC.charge_percent, Literal(x))]) for x in (70, 65)]
        wait_for(lambda: [ch.id for ch in on_c] == ids, 10, "the changes written during the cut")
