"""`tspace write / query / watch / take`: what a person at a shell sees."""

import json
import subprocess
import threading

import pytest

from conftest import free_port, tspace_cmd, wait_for

ROBOT_TTL = """@prefix ac: <https://w3id.org/tspace/selfconfig#> .
@prefix owl: <http://www.w3.org/2002/07/owl#> .
ac:battery_level a owl:FunctionalProperty .
ac:robot1 a ac:Robot ; ac:has_device ac:robot1_battery, ac:robot1_base .
ac:robot1_battery a ac:Battery ; ac:battery_level "normal" .
"""
LOW_TTL = """@prefix ac: <https://w3id.org/tspace/selfconfig#> .
ac:robot1_battery ac:battery_level "very low" .
"""


def test_write_file_then_template_query_as_table(run_tspace, tmp_path):
    doc = tmp_path / "robot.ttl"
    doc.write_text(ROBOT_TTL)
    written = run_tspace("write", str(doc))
    assert written.returncode == 0, written.stderr
    assert len(written.stdout.strip()) == 32  # the changeset id
    out = run_tspace("query", "--template", "ac:robot1 ac:has_device ?d")
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[0].strip() == "d"
    assert sorted(out.stdout.splitlines()[2:]) == ["ac:robot1_base", "ac:robot1_battery"]


def test_write_from_stdin_replaces_functional_value(run_tspace):
    assert run_tspace("write", "-", stdin=ROBOT_TTL).returncode == 0
    assert run_tspace("write", "-", stdin=LOW_TTL).returncode == 0
    out = run_tspace("query", "--template", "?b ac:battery_level ?l", "--format", "json")
    result = json.loads(out.stdout)
    assert result["head"]["vars"] == ["b", "l"]
    assert [b["l"]["value"] for b in result["results"]["bindings"]] == ["very low"]


def test_remove_option_removes_triples(run_tspace, tmp_path):
    run_tspace("write", "-", stdin=ROBOT_TTL)
    doc = tmp_path / "gone.ttl"
    doc.write_text(ROBOT_TTL.split("\n", 2)[0] + "\nac:robot1 ac:has_device ac:robot1_base .")
    assert run_tspace("write", "--remove", str(doc)).returncode == 0
    out = run_tspace("query", "ASK { ac:robot1 ac:has_device ac:robot1_base }")
    assert out.stdout.strip() == "no"


def test_sparql_select_json_is_sparql_results_format(run_tspace):
    run_tspace("write", "-", stdin=ROBOT_TTL)
    out = run_tspace(
        "query", "SELECT ?d WHERE { ac:robot1 ac:has_device ?d } ORDER BY ?d", "-f", "json"
    )
    data = json.loads(out.stdout)
    assert [b["d"]["value"].rsplit("#")[1] for b in data["results"]["bindings"]] == [
        "robot1_base",
        "robot1_battery",
    ]


def test_construct_as_turtle(run_tspace):
    run_tspace("write", "-", stdin=ROBOT_TTL)
    out = run_tspace(
        "query", "CONSTRUCT { ?d ac:part_of ?r } WHERE { ?r ac:has_device ?d }", "-f", "turtle"
    )
    assert out.returncode == 0, out.stderr
    assert "ac:robot1_base ac:part_of ac:robot1 ." in out.stdout


def test_take_prints_and_removes(run_tspace):
    run_tspace("write", "-", stdin=ROBOT_TTL)
    out = run_tspace("take", "?b ac:battery_level ?l")
    assert out.returncode == 0, out.stderr
    assert 'ac:battery_level "normal"' in out.stdout
    left = run_tspace("query", "--template", "?b ac:battery_level ?l")
    assert left.stdout.splitlines()[2:] == []


def test_watch_prints_plus_and_minus_lines(server, space_name, run_tspace):
    run_tspace("write", "-", stdin=ROBOT_TTL)
    cmd = tspace_cmd(
        "watch", "?b ac:battery_level ?l", "--connect", server.endpoint, "--space", space_name
    )
    watcher = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines: list[str] = []
    threading.Thread(
        target=lambda: lines.extend(iter(watcher.stdout.readline, "")), daemon=True
    ).start()
    try:
        # the watcher has subscribed once a write made after its start shows up
        def shows_change() -> bool:
            run_tspace("write", "-", stdin=LOW_TTL.replace("very low", "low"))
            run_tspace("write", "-", stdin=LOW_TTL)
            return any("very low" in line for line in lines)

        wait_for(shows_change, 20, "the watcher's output")
        assert '+ ac:robot1_battery ac:battery_level "very low"\n' in lines
        assert '- ac:robot1_battery ac:battery_level "low"\n' in lines
    finally:
        watcher.terminate()
        watcher.wait(timeout=10)


def test_no_router_is_one_clear_line_and_exit_1():
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    out = subprocess.run(
        tspace_cmd("query", "ASK {?s ?p ?o}", "--connect", endpoint),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert out.returncode == 1
    assert out.stderr.strip() == f"tspace query: no Zenoh router reachable at {endpoint}"


def test_bad_turtle_names_the_line(run_tspace):
    out = run_tspace("write", "-", stdin="@prefix ac: <urn:x#> .\n\nac:a ac:b .\n")
    assert out.returncode == 1
    assert len(out.stderr.strip().splitlines()) == 1
    assert "line 3" in out.stderr and "<stdin>" in out.stderr


def test_missing_file_is_a_clear_error(run_tspace, tmp_path):
    out = run_tspace("write", str(tmp_path / "nope.ttl"))
    assert out.returncode == 1
    assert "nope.ttl: No such file or directory" in out.stderr


def test_bad_sparql_is_one_line_with_position(run_tspace):
    assert run_tspace("write", "-", stdin="<urn:a> <urn:b> <urn:c> .").returncode == 0
    out = run_tspace("query", "SELECT WHERE {")
    assert out.returncode == 1
    assert len(out.stderr.strip().splitlines()) == 1
    assert "line 1, column 15" in out.stderr  # Oxigraph places it at the end of the text


@pytest.mark.parametrize("command", ["serve", "up"])
def test_a_taken_port_is_one_line_and_exit_1_before_starting_anything(server, tmp_path, command):
    out = subprocess.run(
        tspace_cmd(command, "--listen", server.endpoint, "--data", str(tmp_path / "data")),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert out.returncode == 1
    expected = f"tspace {command}: cannot listen on {server.endpoint}: address already in use\n"
    assert out.stderr == expected
    assert not (tmp_path / "data").exists()  # no store, no agent was started


@pytest.mark.parametrize(
    "command",
    [
        ["query", "ASK {}", "--connect"],
        ["write", "-", "--connect"],
        ["watch", "--connect"],
        ["take", "?s ?p ?o", "--connect"],
        ["serve", "--listen", "tcp/127.0.0.1:0", "--connect"],
        ["up", "--listen"],
        ["agent", "hw_monitor", "--robot", "robot1", "--connect"],
    ],
    ids=lambda c: c[0],
)
def test_a_malformed_endpoint_is_one_line_and_exit_1_for_every_command(command, tmp_path):
    out = subprocess.run(
        tspace_cmd(*command, "foo:bar", *(["--data", str(tmp_path)] if command[0] == "up" else [])),
        input="",
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert out.returncode == 1
    assert len(out.stderr.splitlines()) == 1, out.stderr
    assert (
        "bad endpoint 'foo:bar': Endpoints must be of the form <protocol>/<address>" in out.stderr
    )


def test_a_bad_space_name_is_one_line_and_exit_1(server):
    out = subprocess.run(
        tspace_cmd("query", "ASK {}", "--connect", server.endpoint, "--space", "bad/name"),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert out.returncode == 1
    assert (
        out.stderr == "tspace query: space name 'bad/name': use letters, digits, '_', '-' or '.'\n"
    )


def test_take_or_turtle_query_with_no_match_prints_nothing(run_tspace):
    assert run_tspace("write", "-", stdin="<urn:a> <urn:b> <urn:c> .").returncode == 0
    for command in (
        ["take", "?s <urn:nothing> ?o"],
        ["query", "-t", "?s <urn:x> ?o", "-f", "turtle"],
    ):
        out = run_tspace(*command)
        assert (out.returncode, out.stdout, out.stderr) == (0, "", "")


def test_a_usage_error_exits_2_with_one_line(run_tspace):
    out = run_tspace("query")
    assert (out.returncode, out.stderr) == (
        2,
        "tspace query: give either SPARQL text or --template\n",
    )


def test_a_write_the_store_is_too_busy_to_acknowledge_says_it_may_still_be_applied(
    run_tspace, tmp_path
):
    big = tmp_path / "big.ttl"
    big.write_text("".join(f"<urn:s{i}> <urn:p> {i} .\n" for i in range(20_000)))
    # the store needs ~0.5 s for it; naming the space, the write is the command's one request
    out = run_tspace("write", str(big), "--space", "default", "--timeout", "0.05")
    assert out.returncode == 1
    assert out.stdout == ""
    assert out.stderr == (
        "tspace write: sending one changeset of 20000 triples…\n"  # 10,000 and more: said
        "tspace write: no answer from the store to the write within 0.05 s "
        "(the changeset may still be applied)\n"
    )

    def count() -> int:
        answer = run_tspace(
            "query", "SELECT (COUNT(*) AS ?n) WHERE { ?s <urn:p> ?o }", "-f", "json"
        )
        if answer.returncode != 0:
            assert "no space" in answer.stderr, answer.stderr  # not written yet
            return 0
        return int(json.loads(answer.stdout)["results"]["bindings"][0]["n"]["value"])

    wait_for(lambda: count() == 20_000, 30, "the late changeset to be applied")
