"""Firings said as sentences, as the live view and the HMI show them."""

from __future__ import annotations

from agentprocs import knowledge
from rdflib import Literal, Namespace

from agents.sentences import firing_sentence
from conftest import AC_NS

AC = Namespace(AC_NS)


def test_the_papers_firing_reads_as_one_sentence():
    graph = knowledge()
    added = [
        (AC.robot1, AC.current_task, AC.task_going_to_dock),
        (AC.robot1_base, AC.motion_speed, Literal("low")),
        (AC.robot1_screen, AC.running_mode, Literal("stand-by")),
        (AC.robot1_speakers, AC.running_mode, Literal("stand-by")),
        (AC.robot1_microphone, AC.running_mode, Literal("stand-by")),
    ]
    removed = [(AC.robot1, AC.current_task, AC.task_idle)]
    cause = [(AC.robot1_battery, AC.battery_level, Literal("very low"))]
    assert firing_sentence(cause, added, removed, graph) == (
        "battery very low → robot1 goes to the dock at low speed; "
        "microphone, screen, speakers stand-by"
    )


def test_speech_a_speed_alone_and_an_unknown_cause():
    graph = knowledge()
    added = [
        (AC.robot1_base, AC.motion_speed, Literal("normal")),
        (AC.robot1, AC.announcement, Literal("Hello")),
    ]
    assert firing_sentence([], added, [], graph, ["some_rule"]) == (
        "some_rule → robot1 moves at normal speed; robot1 says “Hello”"
    )
    # A property the wording does not know is said as subject, property, value.
    said = firing_sentence(
        [(AC.robot1_laser, AC.obstacles, Literal("surrounded"))],
        [(AC.robot1_base, AC.obstacle_avoidance, Literal("cautious"))],
        [],
        graph,
    )
    assert said == "laser obstacles surrounded → base obstacle avoidance cautious"
