"""The reasoner agent runs every rule form a Jena user writes: backward rules and rules
nested in heads, loaded from a rules file, conclude into the space (as Jena's hybrid mode)
beside the shipped production rules, and go when their premises go."""

import shutil

from agentprocs import HOSPITAL, REPO, value
from rdflib import RDF, Literal, Namespace

from conftest import AC_NS, wait_for

AC = Namespace(AC_NS)
EX = Namespace("http://example.org/site#")

JENA_FORMS = """
@prefix ex: <http://example.org/site#>.
# Backward: a robot at a place is near it (asked of the forward closure, as in Jena).
[near: (?r ex:near ?place) <- (?r ex:at ?place)]
# Nested: a property with a marked domain types what uses it (an instance rule per mark).
[marked: (?p ex:marksAs ?c) -> [(?x rdf:type ?c) <- (?x ?p ?y)]]
# Forward, over the forward closure only: never sees what `near` concludes.
[close: (?r ex:near ?place) -> (?r ex:close ?place)]
"""


def inferred(ts, triple):
    return len(ts.query(triple, graph="inferred")) == 1


def test_backward_and_nested_rules_in_a_rules_file_conclude_into_the_space(ts, launch, tmp_path):
    rules = tmp_path / "rules"
    rules.mkdir()
    for name in ("selfconfig.rules", "paper.rules"):
        shutil.copy(REPO / "rules" / name, rules / name)
    main = rules / "selfconfig.rules"
    main.write_text(main.read_text() + JENA_FORMS)
    agent = launch.start("reasoner", "--robot-file", str(HOSPITAL), "--rules", str(main))
    # Its start (a Python process, Zenoh, the rules and ontology) is slow on a loaded machine.
    wait_for(lambda: "loaded" in agent.logs(), 30, "the reasoner loaded", agent.logs)

    ts.write([(AC.robot1, EX.at, EX.dock), (EX.carries, EX.marksAs, EX.Carrier)])
    wait_for(lambda: inferred(ts, (AC.robot1, EX.near, EX.dock)))
    ts.write([(AC.robot1, EX.carries, EX.tray)])
    wait_for(lambda: inferred(ts, (AC.robot1, RDF.type, EX.Carrier)))
    # The shipped production rules still answer beside them.
    ts.write([(AC.robot1_laser, AC.obstacles, Literal("surrounded"))])
    wait_for(lambda: value(ts, AC.robot1_base, AC.obstacle_avoidance) == Literal("cautious"))
    assert not ts.query((AC.robot1, EX.close, EX.dock))  # as Jena: forward rules miss it

    # Each conclusion goes with its premise: the backward rule's and the nested rule's.
    ts.remove([(AC.robot1, EX.at, EX.dock)])
    wait_for(lambda: not ts.query((AC.robot1, EX.near, EX.dock)))
    ts.remove([(EX.carries, EX.marksAs, EX.Carrier)])
    wait_for(lambda: not ts.query((AC.robot1, RDF.type, EX.Carrier)))
    assert agent.alive()


def test_a_backward_rule_added_to_the_rules_file_is_loaded_without_a_restart(ts, launch, tmp_path):
    rules = tmp_path / "site.rules"
    rules.write_text(
        "@prefix ex: <http://example.org/site#>.\n[f: (?r ex:at ?p) -> (?r ex:was ?p)]\n"
    )
    agent = launch.start("reasoner", "--robot-file", str(HOSPITAL), "--rules", str(rules))
    # Its start (a Python process, Zenoh, the rules and ontology) is slow on a loaded machine.
    wait_for(lambda: "loaded" in agent.logs(), 30, "the reasoner loaded", agent.logs)
    ts.write([(AC.robot1, EX.at, EX.dock)])
    wait_for(lambda: inferred(ts, (AC.robot1, EX.was, EX.dock)))

    rules.write_text(rules.read_text() + "[near: (?r ex:near ?p) <- (?r ex:at ?p)]\n")
    wait_for(lambda: "rules reloaded" in agent.logs(), 30, "the rules reloaded", agent.logs)
    wait_for(lambda: inferred(ts, (AC.robot1, EX.near, EX.dock)))
    assert inferred(ts, (AC.robot1, EX.was, EX.dock))
