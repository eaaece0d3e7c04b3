"""The CLI helps: `tspace up`'s space by default, unknown spaces named, bad input in one line."""

from __future__ import annotations

import re
import subprocess

import pytest

from conftest import REPO, Server, tspace_cmd

ROBOT = "@prefix ac: <https://w3id.org/tspace/selfconfig#> .\nac:robot1 ac:battery_level 'low' .\n"


def tspace(*args: str, stdin: str | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        tspace_cmd(*args), input=stdin, capture_output=True, text=True, timeout=60
    )


@pytest.fixture
def lone_server(tmp_path):
    """A store of its own: the spaces it holds are the test's."""
    srv = Server(tmp_path / "data")
    srv.start()
    try:
        yield srv
    finally:
        srv.stop()


def test_the_default_space_is_the_one_the_store_holds(lone_server):
    connect = ("--connect", lone_server.endpoint)
    assert tspace("write", "-", *connect, "--space", "hospital", stdin=ROBOT).returncode == 0
    # No --space: the one space the store holds (the one `tspace up` runs).
    out = tspace("query", "-t", "?r ac:battery_level ?l", *connect)
    assert out.returncode == 0, out.stderr
    assert "ac:robot1" in out.stdout and "low" in out.stdout
    # A misspelled space is an error naming the spaces there are, not an empty answer.
    out = tspace("query", "-t", "?r ac:battery_level ?l", *connect, "--space", "hopsital")
    assert (out.returncode, out.stdout) == (1, "")
    assert out.stderr == "tspace query: no space 'hopsital' in the store; it holds: hospital\n"
    # Writing names a space into being; then two spaces: which one must be said.
    assert tspace("write", "-", *connect, "--space", "ward", stdin=ROBOT).returncode == 0
    out = tspace("take", "?r ac:battery_level ?l", *connect)
    assert out.returncode == 2
    assert (
        out.stderr == "tspace take: the store holds several spaces (hospital, ward): give --space\n"
    )


def test_bad_documents_are_one_line_and_write_nothing(lone_server, tmp_path):
    connect = ("--connect", lone_server.endpoint, "--space", "hospital")
    assert tspace("write", "-", *connect, stdin=ROBOT).returncode == 0
    cases = {
        "bad.ttl": (
            b"@prefix ac: <urn:x#> .\nac:a ac:b ac:c\nac:d ac:e ac:f .\n",
            "bad.ttl: bad Turtle: line 3: ",
        ),
        "binary.ttl": (bytes(range(256)) * 4, "binary.ttl: a binary file, not Turtle text"),
        "latin1.ttl": (b'<urn:a> <urn:b> "caf\xe9" .\n', "latin1.ttl: line 1: not UTF-8 text"),
        "typed.ttl": (
            b"@prefix xsd: <http://www.w3.org/2001/XMLSchema#> .\n\n"
            b'<urn:a> <urn:b> "abc"^^xsd:integer .\n',
            "typed.ttl: line 3: literal 'abc' is not a valid xsd:integer",
        ),
        "empty.ttl": (b"", "empty.ttl: no triples in it; nothing written"),
        "comments.ttl": (b"# nothing but a comment\n", "comments.ttl: no triples in it"),
    }
    for name, (data, message) in cases.items():
        path = tmp_path / name
        path.write_bytes(data)
        out = tspace("write", str(path), *connect)
        assert out.returncode == 1, (name, out.stderr)
        assert len(out.stderr.splitlines()) == 1 and out.stdout == "", (name, out.stderr)
        assert out.stderr.startswith(f"tspace write: {tmp_path}/{message}"), (name, out.stderr)
    out = tspace("query", "SELECT (COUNT(*) AS ?n) WHERE { ?s ?p ?o }", *connect, "-f", "json")
    assert '"value": "1"' in out.stdout, out.stdout  # only the robot's one triple
    # A UTF-8 byte-order mark (as some editors write) is fine.
    bom = tmp_path / "bom.ttl"
    bom.write_bytes(b"\xef\xbb\xbf<urn:a> <urn:b> <urn:c> .\n")
    out = tspace("write", str(bom), *connect)
    assert out.returncode == 0 and len(out.stdout.strip()) == 32, out.stderr


def test_a_big_document_says_how_far_it_is(lone_server, tmp_path):
    big = tmp_path / "big.ttl"
    # Long literals: over 1 MB in few triples, so that parsing stays quick on a busy machine.
    big.write_text("".join(f'<urn:s{i}> <urn:p> "{i:0>100}" .\n' for i in range(10_000)))
    size = big.stat().st_size / 1e6
    # --atomic: one changeset, all or nothing (without it, tests/test_cli_bulk.py)
    connect = ("--connect", lone_server.endpoint, "--space", "big", "--timeout", "30")
    out = tspace("write", str(big), "--atomic", *connect)
    assert out.returncode == 0, out.stderr
    lines = out.stderr.splitlines()
    assert lines[0] == f"tspace write: reading {big} ({size:.1f} MB)…", lines
    assert lines[1].startswith("tspace write: 10000 triples read in "), lines
    assert lines[2] == "tspace write: sending one changeset of 10000 triples…", lines
    assert re.fullmatch(r"tspace write: written in \d+\.\d s", lines[3]), lines
    assert len(lines) == 4, lines


def test_many_triples_in_a_small_document_say_how_far_the_write_is(lone_server, tmp_path):
    many = tmp_path / "many.ttl"
    many.write_text("".join(f"<urn:s{i}> <urn:p> <urn:o> .\n" for i in range(10_000)))
    assert many.stat().st_size < 1e6  # read at once; the store's part takes the time
    out = tspace(
        "write", str(many), "--connect", lone_server.endpoint, "--space", "many", "--timeout", "30"
    )
    assert out.returncode == 0, out.stderr
    lines = out.stderr.splitlines()
    assert lines[0] == "tspace write: sending one changeset of 10000 triples…", lines
    assert re.fullmatch(r"tspace write: written in \d+\.\d s", lines[1]), lines


def test_version_and_every_commands_help():
    out = tspace("--version")
    assert out.returncode == 0 and out.stdout.startswith("tspace 0."), out
    for command in (
        "serve",
        "write",
        "query",
        "watch",
        "take",
        "why",
        "rules",
        "reason",
        "up",
        "agent",
    ):
        out = tspace(command, "--help")
        assert out.returncode == 0, (command, out.stderr)
        assert out.stdout.startswith(f"usage: tspace {command} "), (command, out.stdout)
    out = tspace("agent", "reasoner", "--help")
    assert out.returncode == 0 and out.stdout.startswith("usage: tspace agent reasoner "), (
        out.stdout
    )


def test_tspace_reason_says_bad_data_in_one_line(tmp_path):
    rules = "rules/paper.rules"
    cases = {
        "bad.ttl": (b"<urn:a> <urn:b> <urn:c>\n<urn:d> <urn:e> .\n", "bad Turtle: line 2: "),
        "binary.ttl": (bytes(range(256)), "a binary file, not Turtle text"),
        "typed.ttl": (
            b'<urn:a> <urn:b> "x"^^<http://www.w3.org/2001/XMLSchema#integer> .\n',
            "line 1: literal 'x' is not a valid xsd:integer",
        ),
    }
    for name, (data, message) in cases.items():
        (tmp_path / name).write_bytes(data)
        out = subprocess.run(
            tspace_cmd("reason", "--rules", str(REPO / rules), "--data", str(tmp_path / name)),
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert out.returncode == 1, (name, out.stderr)
        assert out.stderr == f"tspace reason: {tmp_path / name}: {message}" + (
            out.stderr.split(message, 1)[1] if message.endswith(": ") else "\n"
        ), (name, out.stderr)
        assert len(out.stderr.splitlines()) == 1, (name, out.stderr)


def test_rules_check_refuses_a_file_without_rules(tmp_path):
    empty = tmp_path / "empty.rules"
    empty.write_text("# nothing yet\n@prefix ac: <https://w3id.org/tspace/selfconfig#>.\n")
    out = tspace("rules", "check", str(empty), str(REPO / "rules" / "paper.rules"))
    assert out.returncode == 1
    assert out.stderr == f"{empty}: no rules in it\n"
    assert "paper.rules: 3 rules" in out.stdout  # the other files are still checked
