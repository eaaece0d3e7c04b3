"""`tspace write` of a big document: checked whole, then streamed as several changesets."""

from __future__ import annotations

import json
import re
import subprocess

import pytest

from conftest import Server, tspace_cmd


def tspace(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(tspace_cmd(*args), capture_output=True, text=True, timeout=120)


@pytest.fixture
def lone_server(tmp_path):
    """A store of its own: the spaces it holds are the test's."""
    srv = Server(tmp_path / "data")
    srv.start()
    try:
        yield srv
    finally:
        srv.stop()


def _count(endpoint: str, space: str) -> int:
    out = tspace(
        "query",
        "SELECT (COUNT(*) AS ?n) WHERE { ?s ?p ?o }",
        "--connect",
        endpoint,
        "--space",
        space,
        "-f",
        "json",
    )
    assert out.returncode == 0, out.stderr
    return int(json.loads(out.stdout)["results"]["bindings"][0]["n"]["value"])


def _never_written(endpoint: str, space: str) -> bool:
    out = tspace("query", "ASK { ?s ?p ?o }", "--connect", endpoint, "--space", space)
    return out.returncode == 1 and f"no space '{space}' in the store" in out.stderr


def _document(path, subjects: int, *, broken_at: int | None = None) -> None:
    """Write a Turtle document of 5 triples a subject (1 MB from ~4,600 subjects)."""
    with open(path, "w") as f:
        f.write("@prefix ex: <urn:bulk:> .\n")
        for i in range(subjects):
            if i == broken_at:
                f.write("ex:broken ex:p .\n")
            f.write(f'ex:s{i} ex:n {i} ; ex:d {i}.5 ; ex:label "thing number {i:0>120}" ; ')
            f.write(f'ex:tag "t"@en ; ex:next [ ex:n {i} ] .\n')


def test_a_big_document_is_streamed_as_changesets_with_progress(lone_server, tmp_path):
    big = tmp_path / "big.ttl"
    _document(big, 5_000)  # 30,000 triples (blank nodes included), 1.1 MB
    assert big.stat().st_size >= 1_000_000
    connect = ("--connect", lone_server.endpoint, "--space", "bulk", "--timeout", "60")
    out = tspace("write", str(big), *connect)
    assert out.returncode == 0, out.stderr
    lines = out.stderr.splitlines()
    assert lines[0].startswith(f"tspace write: checking {big} ("), lines
    assert re.fullmatch(r"tspace write: 30,000 triples in [0-9.]+ s; sending…", lines[1]), lines
    assert re.fullmatch(
        r"tspace write: 30,000 of 30,000 triples written \(100%\), [0-9,]+ triples/s: "
        r"3 changesets in [0-9.]+ s; each was applied whole, the document as a whole is not "
        r"atomic \(--atomic\)",
        lines[-1],
    ), lines
    ids = out.stdout.split()
    assert len(ids) == 3 and len(set(ids)) == 3, out.stdout
    assert _count(lone_server.endpoint, "bulk") == 30_000
    # Again: every triple is there already, so nothing changes (a cut run is completed so).
    again = tspace("write", str(big), *connect)
    assert again.returncode == 0, again.stderr
    # ... but a blank node is a new node each time: `ex:next [ ex:n i ]` adds two triples.
    assert _count(lone_server.endpoint, "bulk") == 30_000 + 2 * 5_000


def test_a_malformed_big_document_writes_nothing(lone_server, tmp_path):
    big = tmp_path / "broken.ttl"
    _document(big, 5_000, broken_at=4_000)
    connect = ("--connect", lone_server.endpoint, "--space", "broken", "--timeout", "60")
    out = tspace("write", str(big), *connect)
    assert out.returncode == 1 and out.stdout == "", out.stderr
    error = out.stderr.splitlines()[-1]
    assert error.startswith(f"tspace write: {big}: bad Turtle: "), error
    assert "line 4002" in error, error  # the broken line, after the prefix and 4,000 subjects
    assert _never_written(lone_server.endpoint, "broken")


def test_atomic_refuses_more_than_one_changeset_holds(lone_server, tmp_path):
    big = tmp_path / "huge.ttl"
    _document(big, 17_000)  # 102,000 triples: over the store's 100,000 a changeset
    connect = ("--connect", lone_server.endpoint, "--space", "huge", "--timeout", "60")
    out = tspace("write", str(big), "--atomic", *connect)
    assert out.returncode == 1 and out.stdout == "", out.stderr
    assert out.stderr == (
        f"tspace write: {big}: 102,000 triples, and a changeset holds at most 100,000: "
        "nothing written (without --atomic it is sent as several changesets)\n"
    )
    assert _never_written(lone_server.endpoint, "huge")
