"""`tspace rules check` and `tspace reason`, as a user runs them."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rdflib import Graph, Literal, Namespace, URIRef

from space.cli import main
from space.reasoning import RuleSyntaxError, default_registry, load_rules
from space.reasoning.parser import check_rules

ROOT = Path(__file__).resolve().parents[1]
AC = Namespace("https://w3id.org/tspace/selfconfig#")


def test_rules_check_lists_rules_with_names(capsys):
    assert main(["rules", "check", str(ROOT / "rules" / "paper.rules")]) == 0
    out = capsys.readouterr().out
    assert "3 rules" in out
    assert "verylow_battery_causes_going_to_dock_task  (production)" in out


def test_rules_check_reports_each_broken_file_and_fails(tmp_path, capsys):
    bad = tmp_path / "bad.rules"
    bad.write_text("[ok: (?a ?b ?c) -> (?a ?b ?c)]\n[r2: (?a ?b ?c) -> frobnicate(?a)]\n")
    good = ROOT / "rules" / "paper.rules"
    assert main(["rules", "check", str(bad), str(good)]) == 1
    captured = capsys.readouterr()
    assert f"{bad}:2:20: in rule 'r2': unknown builtin 'frobnicate'" in captured.err
    assert "3 rules" in captured.out


BROKEN = """@prefix ac: <https://w3id.org/tspace/selfconfig#>.
[ok1: (?a ac:p ?b) -> (?b ac:q ?a)]
[open_paren: (?a ac:p ?b -> (?b ac:q ?a)]
[no_builtin: (?a ac:p ?b) -> frobnicate(?a)]
[ok2: (?a ac:p ?b) -> (?b ac:r ?a)]
no_prefix: (?a zz:p ?b) -> (?b ac:r ?a) .
ok3: (?a ac:p ?b) -> (?b ac:s ?a) .
[two_nodes: (?a ac:p) -> (?a ac:t ?a)]
[not_closed: (?a ac:p ?b) -> (?b ac:r ?a)
[ok4: (?a ac:p ?b) -> (?b ac:t ?a)]
"""
ALSO_BROKEN = """[bad_drop: (?a ?b ?c) -> drop(7)]
[fine: (?a ?b ?c) -> (?c ?b ?a)]
[not_closed: (?a ?b ?c) -> (?a ?b ?c)
[inner_error: (?a ?b ?c) -> nosuch(?a)]
[after: (?a ?b ?c) -> (?a ?b ?c)]
unbracketed: (?a ?b ?c) -> ?a .
[last: (?a ?b ?c) -> (?a ?b ?c)]
"""


def test_rules_check_reports_every_error_in_every_file(tmp_path, capsys):
    one, two = tmp_path / "one.rules", tmp_path / "two.rules"
    one.write_text(BROKEN)
    two.write_text(ALSO_BROKEN)
    good = ROOT / "rules" / "paper.rules"
    assert main(["rules", "check", str(one), str(good), str(two)]) == 1
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"{one}:3:26: in rule 'open_paren': syntax error: unexpected '->' (a '(' is not closed)",
        f"{one}:4:30: in rule 'no_builtin': unknown builtin 'frobnicate'",
        f"{one}:6:16: in rule 'no_prefix': unknown prefix 'zz:'",
        f"{one}:8:13: in rule 'two_nodes': a triple has 3 nodes, this one has 2",
        f"{one}:11:1: syntax error: unexpected end of file: expected ']' to close rule "
        "'not_closed' opened at line 9",
        f"{two}:1:26: in rule 'bad_drop': drop(7): the body has only item 0",
        f"{two}:4:29: in rule 'inner_error': unknown builtin 'nosuch'",
        f"{two}:3:1: in rule 'not_closed': syntax error: this '[' is never closed "
        "(a ']' is missing)",
        f"{two}:6:28: in rule 'unbracketed': unknown builtin '?a'",
        "tspace rules: 9 errors in 2 files",
    ]
    assert f"{good}: 3 rules" in captured.out  # a good file among broken ones is still listed
    assert str(one) not in captured.out and str(two) not in captured.out


def test_rules_check_rejects_an_empty_file_and_one_of_comments(tmp_path, capsys):
    empty, comments = tmp_path / "empty.rules", tmp_path / "comments.rules"
    empty.write_text("")
    comments.write_text("# nothing yet\n// nor here\n")
    assert main(["rules", "check", str(empty), str(comments)]) == 1
    assert capsys.readouterr().err.splitlines() == [
        f"{empty}: no rules in it",
        f"{comments}: no rules in it",
        "tspace rules: 2 errors in 2 files",
    ]


def test_a_file_with_errors_refuses_to_load_naming_the_first(tmp_path):
    one = tmp_path / "one.rules"
    one.write_text(BROKEN)
    with pytest.raises(RuleSyntaxError) as raised:
        load_rules([one], default_registry())
    assert str(raised.value) == (
        f"{one}:3:26: in rule 'open_paren': syntax error: unexpected '->' (a '(' is not "
        "closed) (and 4 more errors: `tspace rules check` lists them)"
    )


def test_reason_prints_the_state_after_the_update(tmp_path, capsys):
    update = tmp_path / "update.ttl"
    update.write_text(f'<{AC.robot1_battery}> <{AC.battery_level}> "very low" .\n')
    args = [
        "reason",
        "--rules", str(ROOT / "rules" / "paper.rules"),
        "--ontology", str(ROOT / "ontology" / "selfconfig.ttl"),
        "--data", str(ROOT / "ontology" / "robots" / "hospital.ttl"),
        "--update", str(update),
        "--show", "asserted",
    ]  # fmt: skip
    assert main(args) == 0
    captured = capsys.readouterr()
    state = Graph().parse(data=captured.out, format="turtle")
    assert set(state.objects(AC.robot1_battery, AC.battery_level)) == {Literal("very low")}
    assert set(state.objects(AC.robot1_base, AC.motion_speed)) == {Literal("low")}
    assert set(state.objects(AC.robot1_speakers, AC.running_mode)) == {Literal("stand-by")}
    assert "fired verylow_battery_causes_low_speed_existing" in captured.err


def test_reason_reports_a_broken_rules_file(tmp_path, capsys):
    bad = tmp_path / "bad.rules"
    bad.write_text("[r: (?a ?b ?c) -> drop(4)]")
    data = tmp_path / "d.ttl"
    data.write_text("")
    assert main(["reason", "--rules", str(bad), "--data", str(data)]) == 1
    assert "in rule 'r': drop(4): the body has only item 0" in capsys.readouterr().err


def test_rules_check_counts_one_rule_in_the_singular(tmp_path, capsys):
    one = tmp_path / "one.rules"
    one.write_text("[only: (?a ?b ?c) -> (?a ?b ?c)]\n")
    assert main(["rules", "check", str(one)]) == 0
    assert f"{one}: 1 rule\n" in capsys.readouterr().out


def test_rules_check_names_a_missing_file_as_given(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["rules", "check", "nofile.rules"]) == 1
    assert capsys.readouterr().err == "nofile.rules: no such file\n"


def test_reason_names_a_missing_data_file_as_given(tmp_path, monkeypatch, capsys):
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    rules = str(ROOT / "rules" / "paper.rules")
    assert main(["reason", "--rules", rules, "--data", "../nofile.ttl"]) == 1
    assert capsys.readouterr().err == "tspace reason: ../nofile.ttl: no such file\n"


def test_reason_reads_relative_iris_against_the_data_file(tmp_path, monkeypatch, capsys):
    (tmp_path / "data.ttl").write_text("<a> <p> <b> .\n")
    monkeypatch.chdir(tmp_path)
    rules = str(ROOT / "rules" / "paper.rules")
    assert main(["reason", "--rules", rules, "--data", "data.ttl"]) == 0
    state = Graph().parse(data=capsys.readouterr().out, format="turtle")
    base = tmp_path.as_uri()
    assert (URIRef(f"{base}/a"), URIRef(f"{base}/p"), URIRef(f"{base}/b")) in state


PIECES = ["[", "]", "(", ")", "->", "<-", ".", "r:", "?a", "?b", "ac:p", "'x'", "'", ",", "\n"]
PIECES += [
    " ",
    "zz:q",
    "42",
    "drop(0)",
    "@prefix ac: <urn:x#>.\n",
    "[n: (?a ac:p ?b) -> (?b ac:p ?a)]\n",
]


@settings(
    max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.lists(st.sampled_from(PIECES), max_size=60))
def test_the_checker_reads_any_text_to_its_end_and_locates_every_error(tmp_path, pieces):
    path = tmp_path / "any.rules"
    path.write_text("".join(pieces))
    rules, errors = check_rules([path], default_registry(), warn=lambda message: None)
    for error in errors:
        assert re.match(rf"{re.escape(str(path))}:\d+:\d+: ", str(error)), str(error)
    if "".join(pieces).count("[n: (?a ac:p ?b) -> (?b ac:p ?a)]\n") and not errors:
        assert rules  # a well-formed rule among well-formed text is read


def test_rules_check_refuses_a_rule_the_engine_cannot_run_as_the_reasoner_would(tmp_path, capsys):
    # It parses, but no order of the body runs it: the reasoner would refuse it at load.
    bad = tmp_path / "bad.rules"
    bad.write_text("[r: (?x <urn:p> ?y), equal(?y, f(?x)) -> (?x <urn:q> ?y)]\n")
    assert main(["rules", "check", str(bad)]) == 1
    assert f"{bad}:1:22: in rule 'r': cannot order the builtins equal" in capsys.readouterr().err


def test_rules_check_and_reason_run_backward_and_nested_rules_as_jena(tmp_path, capsys):
    rules = tmp_path / "mixed.rules"
    rules.write_text(
        "@prefix ex: <http://example.org/>.\n"
        "[dom: (?p ex:domain ?c) -> [(?x rdf:type ?c) <- (?x ?p ?y)]]\n"
        "[back: (?x ex:near ?y) <- (?x ex:at ?y)]\n"
        "[fwd: (?x ex:near ?y) -> (?x ex:close ?y)]\n"
    )
    assert main(["rules", "check", str(rules)]) == 0
    out = capsys.readouterr().out
    assert "dom  (backward, monotonic)" in out and "back  (backward, monotonic)" in out
    assert "fwd  (monotonic)" in out
    data = tmp_path / "d.ttl"
    data.write_text(
        "@prefix ex: <http://example.org/>.\nex:drives ex:domain ex:Robot.\n"
        "ex:r1 ex:drives ex:base1 ; ex:at ex:dock.\n"
    )
    assert main(["reason", "--rules", str(rules), "--data", str(data)]) == 0
    state = Graph().parse(data=capsys.readouterr().out, format="turtle")
    ex = Namespace("http://example.org/")
    assert (ex.r1, URIRef("http://www.w3.org/1999/02/22-rdf-syntax-ns#type"), ex.Robot) in state
    assert (ex.r1, ex.near, ex.dock) in state
    assert (ex.r1, ex.close, ex.dock) not in state  # Jena's forward rules never see it
