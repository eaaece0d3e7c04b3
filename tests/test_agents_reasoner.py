"""The reasoner as a process: the paper's example end to end, provenance, reload, restart."""

import shutil
import signal
import threading

import msgpack
import zenoh
from agentprocs import HOSPITAL, REPO, value
from rdflib import RDF, Literal, Namespace

from agents.firings import rule_names
from conftest import AC_NS, wait_for
from space.zconfig import make_config

AC = Namespace(AC_NS)


def firings(ts, rule=None):
    """Return {record: (rule names, cause)} of the firing records in the space."""
    found = {}
    for record in ts.query((None, RDF.type, AC.RuleFiring)).subjects():
        names = set(rule_names(ts.query((record, AC.rule_names, None))))
        if rule is None or rule in names:
            found[record] = (names, str(value(ts, record, AC.cause)))
    return found


def test_the_papers_example_very_low_battery(ts, launch):
    """Section 3.3: very low battery -> dock, low speed, interaction devices on stand-by."""
    launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle)
    # Away from its dock: at the dock a robot going to charge charges at once, and its
    # battery would leave "very low" before the test could see what it caused.
    ts.write(
        [(AC.robot1_battery, AC.charge_percent, Literal(12)), (AC.robot1, AC.location, AC.hall)]
    )
    seen = []
    lock = threading.Lock()

    def on_level(change):
        with lock:
            seen.extend((change.id, o) for _s, _p, o in change.added)

    ts.subscribe((AC.robot1_battery, AC.battery_level, None), on_level)
    launch.start("hw_monitor", "--time-scale", "100")

    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_going_to_dock, 20)
    wait_for(lambda: value(ts, AC.robot1_base, AC.motion_speed) == Literal("low"))
    for device in (AC.robot1_screen, AC.robot1_speakers, AC.robot1_microphone):
        wait_for(lambda d=device: value(ts, d, AC.running_mode) == Literal("stand-by"))
        wait_for(lambda d=device: value(ts, d, AC.actual_mode) == Literal("stand-by"))
    assert value(ts, AC.robot1_wheels, AC.running_mode) == Literal("active")
    # The reasoner's OWL RL conclusions are in the inferred graph.
    assert len(ts.query((AC.robot1_screen, RDF.type, AC.InteractionDevice), graph="inferred"))

    with lock:
        very_low = [cs for cs, level in seen if level == Literal("very low")]
    assert len(very_low) == 1
    records = firings(ts, "verylow_battery_causes_low_speed_existing")
    assert [cause for _rules, cause in records.values()] == very_low
    record = next(iter(records))
    assert value(ts, record, AC.robot) == AC.robot1
    # One record answers the change, naming each rule that fired (the devices went to
    # stand-by already when the battery was low).
    assert records[record][0] == {
        "verylow_battery_causes_low_speed_existing",
        "verylow_battery_causes_going_to_dock_task",
    }


def test_rules_are_reloaded_and_a_broken_file_keeps_the_old_rules(ts, launch, tmp_path):
    rules = tmp_path / "rules"
    rules.mkdir()
    for name in ("selfconfig.rules", "paper.rules"):
        shutil.copy(REPO / "rules" / name, rules / name)
    main = rules / "selfconfig.rules"
    agent = launch.start("reasoner", "--robot-file", str(HOSPITAL), "--rules", str(main))
    wait_for(lambda: "loaded" in agent.logs())

    main.write_text(main.read_text() + "\n[broken: (?a ac:b ?c) -> \n")
    wait_for(lambda: "rules not reloaded" in agent.logs())
    assert "selfconfig.rules:" in agent.logs().split("rules not reloaded")[1]
    ts.write([(AC.robot1_laser, AC.obstacles, Literal("surrounded"))])
    wait_for(lambda: value(ts, AC.robot1_base, AC.obstacle_avoidance) == Literal("cautious"))

    text = main.read_text().replace("\n[broken: (?a ac:b ?c) -> \n", "")
    main.write_text(text + "\n[in_the_hall: (?r ac:location ac:hall) -> (?r ac:near ac:hall)]\n")
    wait_for(lambda: "rules reloaded" in agent.logs())
    ts.write([(AC.robot1, AC.location, AC.hall)])
    wait_for(lambda: len(ts.query((AC.robot1, AC.near, AC.hall), graph="inferred")) == 1)
    assert agent.alive()


def test_kill_9_then_restart_answers_again_without_duplicating_conclusions(ts, launch):
    agent = launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle)
    ts.write([(AC.robot1, AC.interacting_with, AC.patient_jon)])
    wait_for(lambda: value(ts, AC.robot1_base, AC.motion_speed) == Literal("low"))
    inferred = set(ts.query(None, graph="inferred"))
    before = max(int(value(ts, f, AC.firing_seq)) for f in firings(ts))

    agent.stop(signal.SIGKILL)
    ts.write([(AC.robot1, AC.interacting_with, AC.patient_ane)])
    agent.start()
    # Rebuilt from the space: it sees the change made while it was down.
    wait_for(lambda: value(ts, AC.robot1_screen, AC.button_press_time) == Literal("long"))
    wait_for(lambda: value(ts, AC.robot1_base, AC.motion_speed) == Literal("normal"))
    after = set(ts.query(None, graph="inferred"))
    assert (AC.robot1, AC.audience_profile, AC.profile_slow_presser) in after
    assert (AC.robot1, AC.audience_profile, AC.profile_wheelchair) not in after
    assert len(after) == len(inferred)
    assert (
        min(
            int(value(ts, f, AC.firing_seq))
            for f in firings(ts, "normal_speed_when_no_reason_to_slow")
        )
        > before
    )


def test_the_whole_robot_goes_to_charge_and_back_to_its_patient(ts, launch):
    """All four agents: very low battery while attending a patient, then charged, back to work."""
    launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle)
    ts.write([(AC.robot1_battery, AC.charge_percent, Literal(16))])
    for agent in ("hw_monitor", "nav_monitor", "behavior"):
        launch.start(agent, "--time-scale", "80")
    ts.write(
        [
            (AC.robot1, AC.attended_person, AC.patient_jon),
            (AC.robot1, AC.requested_task, AC.task_attending_patient),
        ]
    )
    wait_for(lambda: value(ts, AC.robot1, AC.location) == AC.room_102, 20)
    # Jon uses a wheelchair: the robot drives slowly with him.
    assert value(ts, AC.robot1_base, AC.motion_speed) == Literal("low")
    wait_for(lambda: value(ts, AC.robot1_battery, AC.battery_level) == Literal("very low"), 30)
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_charging, 30)
    assert value(ts, AC.robot1, AC.location) == AC.dock1
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_attending_patient, 60)
    wait_for(lambda: value(ts, AC.robot1, AC.location) == AC.room_102, 20)
    assert value(ts, AC.robot1_speakers, AC.running_mode) == Literal("active")


def test_a_term_it_cannot_parse_drops_that_change_only(ts, server, launch):
    """Changes reach the reasoner as N-Triples texts, parsed when its engine first meets a
    term: a change with a term that does not parse (here forged on the changes key, as the
    store never publishes one) is logged and skipped, and the next one is answered."""
    agent = launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle)
    seq = ts.write([(AC.robot1, AC.location, AC.hall)]).seq
    forged = {
        "v": 1,
        "id": "forged",
        "agent": "intruder",
        "seq": seq + 1,  # the next one: the reasoner takes it as the store's
        "add": [[f"<{AC_NS}robot1_battery>", f"<{AC_NS}battery_level>", '"very low']],
    }
    with zenoh.open(make_config(connect=[server.endpoint])) as plain:
        plain.put(f"tspace/{ts.space}/@/changes", msgpack.packb(forged))
    wait_for(lambda: "change forged: not an N-Triples literal" in agent.logs(), 10, "the warning")
    ts.write([(AC.robot1, AC.location, AC.hall_east)])  # the seq the forged change took
    ts.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))])
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_going_to_dock, 20)
    assert agent.alive()
    assert value(ts, AC.robot1_battery, AC.battery_level) == Literal("very low")
