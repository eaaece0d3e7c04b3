"""`why`: the reasoner explains a conclusion down to what agents wrote (API, CLI, wire)."""

from __future__ import annotations

import json
import subprocess
import sys
from datetime import UTC, datetime

import pytest
from agentprocs import HOSPITAL, value
from rdflib import RDF, Literal, Namespace

from conftest import AC_NS, REPO, wait_for
from space import NoReasoner, TripleSpace

AC = Namespace(AC_NS)
LOW_SPEED = "verylow_battery_causes_low_speed_existing"


@pytest.fixture
def very_low(ts, launch):
    """A reasoner on the hospital robot, whose battery a test client set to very low."""
    reasoner = launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle, 30, "the robot")
    written = ts.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))])
    wait_for(lambda: value(ts, AC.robot1_base, AC.motion_speed) == Literal("low"), 20)
    return written, reasoner


def test_a_conclusion_is_explained_down_to_who_wrote_each_fact(ts, very_low):
    written, _reasoner = very_low
    [tree] = ts.why((AC.robot1_base, AC.motion_speed, None))
    assert tree.triple == (AC.robot1_base, AC.motion_speed, Literal("low"))
    assert tree.holds == "asserted" and tree.rule == LOW_SPEED
    assert tree.comment == "Figure 5: a very low battery sets a low motion speed."
    assert tree.where is not None and tree.where.endswith("paper.rules:9")
    premises = {p.triple: p for p in tree.premises}
    level = premises[(AC.robot1_battery, AC.battery_level, Literal("very low"))]
    assert level.rule is None and level.written is not None
    assert (level.written.agent, level.written.changeset) == ("test", written)
    assert level.written.seq > 0 and level.written.time is not None
    # The speed the rule replaced held when it fired, and holds no more.
    assert premises[(AC.robot1_base, AC.motion_speed, Literal("normal"))].holds == "gone"
    # What the reasoner loaded at start (the robot file it wrote) is found in the store's log.
    robot = premises[(AC.robot1, RDF.type, AC.Robot)]
    assert robot.written is not None and robot.written.agent == "reasoner"
    # A fact matched twice in one tree is explained once.
    assert all(node.premises == () for _d, node in tree.walk() if node.repeated)


def test_an_owl_entailment_names_its_owl_rl_rule_and_the_axiom(ts, very_low):
    [tree] = ts.why((AC.robot1_screen, RDF.type, AC.InteractionDevice))
    assert tree.holds == "inferred" and tree.rule == "cax-sco"
    assert tree.comment is not None and "superclass" in tree.comment
    assert any(p.triple[1] == RDF.type and p.triple[0] == AC.robot1_screen for p in tree.premises)


def test_tspace_why_prints_the_tree_and_json(ts, very_low, run_tspace):
    written, _reasoner = very_low
    ts.load_prefixes()
    done = run_tspace("why", "ac:robot1_base ac:motion_speed ?speed")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == 'ac:robot1_base ac:motion_speed "low"'
    assert f"by production rule {LOW_SPEED} (" in done.stdout
    assert "“Figure 5: a very low battery sets a low motion speed.”" in done.stdout
    assert any('ac:robot1_battery ac:battery_level "very low"' in line for line in lines)
    assert "written by test at " in done.stdout

    done = run_tspace("why", "--format", "json", "ac:robot1_base ac:motion_speed ?speed")
    assert done.returncode == 0, done.stderr
    [tree] = json.loads(done.stdout)
    assert tree["rule"] == LOW_SPEED and tree["holds"] == "asserted"
    level = next(p for p in tree["premises"] if p["text"].endswith('battery_level "very low"'))
    assert level["written"]["agent"] == "test" and level["written"]["changeset"] == written


def test_nothing_holding_and_no_reasoner_are_one_line_errors(ts, very_low, run_tspace, server):
    done = run_tspace("why", "ac:robot1 ac:current_task ac:task_guiding")
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr.strip() == (
        "tspace why: nothing matching 'ac:robot1 ac:current_task ac:task_guiding' holds"
    )
    with TripleSpace.open(server.endpoint, space="nobody_reasons") as other:
        with pytest.raises(NoReasoner, match="no reasoner answered on space 'nobody_reasons'"):
            other.why(None, timeout=0.5)


def test_a_malformed_why_request_gets_an_error_and_the_reasoner_lives_on(ts, very_low):
    _written, reasoner = very_low
    replies = list(ts.session.get(f"tspace/{ts.space}/@/why", payload=b"\xc1", timeout=5))
    assert [r.err is not None for r in replies] == [True]
    assert "msgpack" in replies[0].err.payload.to_string()
    assert reasoner.alive()
    assert len(ts.why((AC.robot1_base, AC.motion_speed, None))) == 1


def test_the_wire_format_example_asks_why_with_zenoh_and_msgpack_only(ts, very_low, server):
    """docs/wire-format.md's example, as written there, on the test's router and space."""
    doc = (REPO / "docs" / "wire-format.md").read_text()
    section = doc.split("### Explanations: `@/why`", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    code = code.replace("tcp/127.0.0.1:7447", server.endpoint)
    code = code.replace("tspace/hospital/", f"tspace/{ts.space}/")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert LOW_SPEED in done.stdout and "motion_speed" in done.stdout, done.stdout


def test_who_wrote_a_literal_the_store_writes_in_another_form_is_named(ts, very_low, server):
    """The store republishes a UTC dateTime with `Z` and 1.0 as `"1"^^xsd:double`; the
    reasoner, which reads changes as texts, still names their writer, and the later one."""
    started = (AC.robot1, AC.task_started, Literal(datetime(2026, 1, 2, 3, 4, 5, tzinfo=UTC)))
    weight = (AC.robot1, AC.payload_kg, Literal(1.0))
    first = ts.write([started, weight])
    with TripleSpace.open(server.endpoint, space=ts.space, agent="other") as other:
        other.remove([weight])
        second = other.write([weight])  # written again: the later writer is named

    def writer(triple: tuple) -> tuple[str, str] | None:
        trees = ts.why(triple)
        if not trees or trees[0].written is None:
            return None
        return trees[0].written.agent, trees[0].written.changeset

    wait_for(lambda: writer(started) == ("test", first), 10, "the first writer")
    wait_for(lambda: writer(weight) == ("other", second), 10, "the second writer")
