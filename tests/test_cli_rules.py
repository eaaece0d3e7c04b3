"""`tspace rules check` and `tspace reason`, as a user runs them."""

from __future__ import annotations

from pathlib import Path

from rdflib import Graph, Literal, Namespace, URIRef

from space.cli import main

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
