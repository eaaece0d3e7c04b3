"""The reasoner never drifts from the space: loops keep the change, lost answers are given."""

from __future__ import annotations

import random
import signal
import threading
from collections import defaultdict

from agentprocs import REPO, knowledge, value
from rdflib import RDF, BNode, Literal, Namespace

from agents.firings import rule_names
from conftest import AC_NS, wait_for
from space import Change, TripleSpace
from space.reasoning import Origin, RuleEngine

AC = Namespace(AC_NS)
EX = Namespace("http://example.org/")
ROUNDS = 5
PATIENTS = [AC.patient_jon, AC.patient_ane]


def test_a_rule_loop_keeps_the_change_and_is_reported_in_the_space(ts, launch, tmp_path):
    rules = tmp_path / "loop.rules"
    rules.write_text(
        "@prefix ex: <http://example.org/>.\n"
        "[ping: (?x ex:state 'a') -> drop(0), (?x ex:state 'b')]\n"
        "[pong: (?x ex:state 'b') -> drop(0), (?x ex:state 'a')]\n"
        "[kind: (?x ex:state ?s) -> (?x ex:kind ex:Stateful)]\n"
    )
    agent = launch.start("reasoner", "--rules", str(rules))
    wait_for(lambda: "loaded" in agent.logs(), 30, "the reasoner", agent.logs)
    ts.write([(EX.x, EX.state, Literal("a"))])
    wait_for(lambda: len(ts.query((EX.x, EX.kind, EX.Stateful))) == 1, 20, "the conclusion")
    assert value(ts, EX.x, EX.state) == Literal("a")
    loops = ts.query((None, RDF.type, AC.RuleLoop))  # OWL RL adds RuleLoop subClassOf itself
    assert len(loops) == 1
    record = next(iter(loops.subjects()))
    assert set(rule_names(ts.query((record, AC.rule_names, None)))) == {"ping", "pong"}
    # It goes on answering.
    ts.write([(EX.y, EX.state, Literal("c"))])
    wait_for(lambda: len(ts.query((EX.y, EX.kind, EX.Stateful))) == 1, 20, "the next answer")
    assert agent.alive()


def test_per_robot_every_change_is_answered_while_its_reasoner_is_killed_in_a_loop(
    ts, launch, server
):
    ts.write(knowledge())
    leader = launch.start("reasoner", "--per-robot", "--robot", "robot2")
    wait_for(lambda: "loaded" in leader.logs(), 30, "the leader", leader.logs)
    owner = launch.start("reasoner", "--per-robot", "--robot", "robot1")
    wait_for(lambda: "loaded" in owner.logs(), 30, "robot1's reasoner", owner.logs)

    answers: dict[str, list[str]] = defaultdict(list)

    def on_change(change: Change) -> None:
        if change.cause and change.agent.startswith("reasoner."):
            answers[change.cause].append(change.agent)

    ts.subscribe(None, on_change)
    stop = threading.Event()

    def noise() -> None:  # other writers keep the store and the reasoners busy meanwhile
        with TripleSpace.open(server.endpoint, space=ts.space, agent="noise") as other:
            n = 0
            while not stop.is_set():
                other.write([(EX.noise, EX.n, Literal(n))])
                n += 1

    writer = threading.Thread(target=noise)
    writer.start()
    written = []
    try:
        for i in range(ROUNDS):
            written.append(ts.write([(AC.robot1, AC.interacting_with, PATIENTS[i % 2])]))
            # Kill it at a random moment around its answer: before, during or after.
            stop.wait(random.uniform(0.0, 0.08))
            owner.stop(signal.SIGKILL)
            owner.start()
            wait_for(
                lambda i=i: owner.logs().count("loaded") == i + 2, 60, "the restart", owner.logs
            )
    finally:
        stop.set()
        writer.join()

    wait_for(
        lambda: all(answers.get(c) for c in written),
        60,
        "an answer to every change",
        lambda: f"unanswered: {[c for c in written if not answers.get(c)]}\n{leader.logs()}",
    )
    last = PATIENTS[(ROUNDS - 1) % 2]
    speed = Literal("low") if last == AC.patient_jon else Literal("normal")
    wait_for(lambda: value(ts, AC.robot1_base, AC.motion_speed) == speed, 20, "the last speed")
    # The space is what the rules make of it: a fresh engine loading it concludes the same
    # (blank nodes aside: the engine reads the ontology's anew).
    asserted = [t for t in ts.query(None, graph="asserted") if "firing_" not in str(t[0])]
    inferred = set(ts.query(None, graph="inferred"))
    engine = RuleEngine.from_files(
        rules=[REPO / "rules" / "selfconfig.rules"], ontology=[REPO / "ontology" / "selfconfig.ttl"]
    )
    delta = engine.load(asserted)
    assert delta.asserted_added == () and delta.asserted_removed == ()
    named = lambda triples: {t for t in triples if not any(isinstance(x, BNode) for x in t)}  # noqa: E731
    assert named(engine.triples(Origin.INFERRED)) == named(inferred)
