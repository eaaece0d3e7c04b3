"""The paper's three rules (Figures 5 and 6, Section 3.3) on its robot, from the real files."""

from __future__ import annotations

from pathlib import Path

import pytest
from rdflib import RDF, Literal, Namespace

from space.reasoning import RuleEngine, read_graph

ROOT = Path(__file__).resolve().parents[1]
AC = Namespace("https://w3id.org/tspace/selfconfig#")
VERY_LOW = (AC.robot1_battery, AC.battery_level, Literal("very low"))
NORMAL = (AC.robot1_battery, AC.battery_level, Literal("normal"))


@pytest.fixture
def robot() -> RuleEngine:
    engine = RuleEngine.from_files(
        rules=[ROOT / "rules" / "paper.rules"], ontology=[ROOT / "ontology" / "selfconfig.ttl"]
    )
    engine.load(read_graph([ROOT / "ontology" / "robots" / "hospital.ttl"]))
    return engine


def modes(engine: RuleEngine) -> dict[str, str]:
    return {
        str(device).rsplit("_", 1)[-1]: str(mode)
        for device, mode in engine.graph.subject_objects(AC.running_mode)
    }


def test_nothing_fires_while_the_battery_is_normal(robot):
    assert set(robot.graph.objects(AC.robot1_base, AC.motion_speed)) == {Literal("normal")}
    assert set(modes(robot).values()) == {"active"}


def test_very_low_battery_slows_down_goes_to_dock_and_puts_interaction_on_standby(robot):
    delta = robot.apply(added=[VERY_LOW], removed=[NORMAL])
    graph = robot.graph
    assert set(graph.objects(AC.robot1_base, AC.motion_speed)) == {Literal("low")}
    assert set(graph.objects(AC.robot1, AC.current_task)) == {AC.task_going_to_dock}
    assert modes(robot) == {
        "battery": "active",
        "base": "active",
        "wheels": "active",
        "laser": "active",
        "screen": "stand-by",
        "speakers": "stand-by",
        "microphone": "stand-by",
    }
    assert [f.rule for f in delta.firings] == [
        "verylow_battery_causes_low_speed_existing",
        "verylow_battery_causes_going_to_dock_task",
        *["verylow_battery_causes_interaction_devices_standby"] * 3,
    ]
    assert all(VERY_LOW in f.triggers for f in delta.firings)
    assert set(delta.asserted_removed) == {
        (AC.robot1_base, AC.motion_speed, Literal("normal")),
        (AC.robot1, AC.current_task, AC.task_idle),
        *(
            (AC[f"robot1_{d}"], AC.running_mode, Literal("active"))
            for d in ("screen", "speakers", "microphone")
        ),
    }


def test_interaction_devices_are_known_from_the_class_hierarchy_only(robot):
    why = robot.why((AC.robot1_microphone, RDF.type, AC.InteractionDevice))
    assert not why.asserted and why.rule == "cax-sco"
    assert robot.why((AC.robot1_wheels, RDF.type, AC.InteractionDevice)) is None


def test_a_second_very_low_report_changes_nothing(robot):
    robot.apply(added=[VERY_LOW], removed=[NORMAL])
    delta = robot.apply(added=[VERY_LOW])
    assert not delta and delta.firings == ()
