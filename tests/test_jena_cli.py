"""`tspace reason` and `tspace rules check` on rule files written for Jena."""

from __future__ import annotations

from rdflib import Graph, Literal, URIRef

from space.cli import main

EX = "http://example.org/"


def _files(tmp_path, rules: str, data: str = "") -> tuple[str, str]:
    (tmp_path / "r.rules").write_text(rules)
    (tmp_path / "d.ttl").write_text(data)
    return str(tmp_path / "r.rules"), str(tmp_path / "d.ttl")


def test_reason_no_owl_prints_valid_turtle_and_print_goes_to_stderr(tmp_path, capsys):
    rules, data = _files(
        tmp_path,
        "@prefix ex: <http://example.org/>\n"
        "(?a ex:p ?b) print('saw', ?a) -> (?b ex:q ?a) .\n"
        "(?a ex:q ?b) -> ('lit' ex:bad ?b) .\n",
        f"<{EX}a> <{EX}p> <{EX}b> .\n",
    )
    assert main(["reason", "--no-owl", "--rules", rules, "--data", data]) == 0
    captured = capsys.readouterr()
    state = Graph().parse(data=captured.out, format="turtle")
    assert (URIRef(EX + "b"), URIRef(EX + "q"), URIRef(EX + "a")) in state
    assert not any(isinstance(s, Literal) for s in state.subjects())
    assert '"saw" <http://example.org/a>' in captured.err
    assert "1 derived triple with a literal subject or predicate not printed" in captured.err
    assert "saw" not in captured.out


def test_reason_no_owl_runs_only_the_rules(tmp_path, capsys):
    ontology = tmp_path / "o.ttl"
    ontology.write_text(f"<{EX}C> <http://www.w3.org/2000/01/rdf-schema#subClassOf> <{EX}D> .\n")
    rules, data = _files(
        tmp_path,
        "[r: (?x <http://example.org/p> ?y) -> (?y <http://example.org/p> ?x)]\n",
        f"<{EX}x> a <{EX}C> .\n",
    )
    base = ["reason", "--rules", rules, "--data", data, "--ontology", str(ontology)]
    assert main([*base, "--no-owl"]) == 0
    plain = Graph().parse(data=capsys.readouterr().out, format="turtle")
    assert main(base) == 0
    with_owl = Graph().parse(data=capsys.readouterr().out, format="turtle")
    entailed = (URIRef(EX + "x"), URIRef("http://www.w3.org/1999/02/22-rdf-syntax-ns#type"),
                URIRef(EX + "D"))  # fmt: skip
    assert entailed in with_owl
    assert entailed not in plain


def test_rules_check_accepts_a_jena_file_with_a_name_used_twice_and_warns(tmp_path, capsys):
    rules, _ = _files(
        tmp_path,
        "# Jena style\n@prefix ex: http://example.org/\n"
        "[r1: (?a ex:p ?b) -> (?b ex:p ?a)]\n"
        "r1: (?a ex:q ?b) -> (?a ex:p ?b) .\n"
        "-> (ex:a ex:q ex:b) .\n",
    )
    assert main(["rules", "check", rules]) == 0
    captured = capsys.readouterr()
    assert "3 rules" in captured.out
    assert (
        f"tspace rules: warning: {rules}:4:1: rule name 'r1' is used again, first at {rules}:3:1"
        in captured.err
    )
    assert f"r1 ({rules}:4)" in captured.out


def test_rules_check_warns_that_a_rule_after_a_prefix_on_its_line_is_dropped(tmp_path, capsys):
    rules, _ = _files(
        tmp_path,
        "@prefix pre: <http://jena.hpl.hp.com/prefix#> [r1: (?f pre:father ?a) -> (?a pre:x ?f)]\n",
    )
    assert main(["rules", "check", rules]) == 1  # a file without rules is a mistake
    captured = capsys.readouterr()
    assert f"{rules}: no rules in it" in captured.err  # as Jena reads it: the line is the prefix's
    assert f"{rules}:1:1: text after @prefix's <...> is ignored" in captured.err


def test_reason_without_an_ontology_runs_only_the_rules(tmp_path, capsys):
    rules, data = _files(
        tmp_path,
        "[r: (?x <http://example.org/p> ?y) -> (?y <http://example.org/p> ?x)]\n",
        f"<{EX}x> <http://www.w3.org/2002/07/owl#sameAs> <{EX}y> .\n<{EX}x> <{EX}p> <{EX}z> .\n",
    )
    assert main(["reason", "--rules", rules, "--data", data]) == 0
    state = Graph().parse(data=capsys.readouterr().out, format="turtle")
    assert (URIRef(EX + "z"), URIRef(EX + "p"), URIRef(EX + "x")) in state
    # OWL RL's equality rules would copy x's triples to y: not without an ontology.
    assert (URIRef(EX + "y"), URIRef(EX + "p"), URIRef(EX + "z")) not in state
