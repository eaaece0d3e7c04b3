"""Writers, store and subscribers as separate processes: order, late joiners, plain Zenoh."""

import json
import subprocess
import threading
from pathlib import Path

from rdflib import Literal, Namespace

from conftest import AC_NS, PYTHON, wait_for

AC = Namespace(AC_NS)
PROGRAMS = Path(__file__).parent / "programs"


class Lines:
    """Collect a child's stdout lines from a thread (the child must flush)."""

    def __init__(self, proc: subprocess.Popen) -> None:
        self.proc = proc
        self.lines: list[str] = []
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.rstrip("\n"))


def program(name: str, *args: str, stdin: bool = False) -> subprocess.Popen:
    return subprocess.Popen(
        [PYTHON, str(PROGRAMS / name), *args],
        stdout=subprocess.PIPE,
        stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
        text=True,
    )


def stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def test_late_joiner_sees_state_then_every_change_without_gap_or_duplicate(server, space_name):
    # 300 changesets over about 3 s, so the subscriber joins while they are being written
    writer = program("writer.py", server.endpoint, space_name, "300", "0.01")
    out = Lines(writer)
    sub = None
    try:
        wait_for(lambda: len(out.lines) >= 100, 30, "the writer's first 100 changesets")
        sub = program("subscriber.py", server.endpoint, space_name)
        got = Lines(sub)
        assert writer.wait(timeout=60) == 0
        wait_for(lambda: len(got.lines) > 1 and _seen(got) == 300, 30, "all 300 triples")
        changes = [json.loads(line) for line in got.lines if "seq" in json.loads(line)]
        snapshot, later = changes[0], changes[1:]
        assert 0 < len(snapshot["added"]) < 300, "the subscriber joined mid-stream"
        seqs = [c["seq"] for c in later]
        assert seqs == list(range(snapshot["seq"] + 1, snapshot["seq"] + 1 + len(later)))
    finally:
        stop(writer)
        if sub is not None:
            stop(sub)


def _seen(lines: Lines) -> int:
    values = set()
    for line in lines.lines:
        for t in json.loads(line).get("added", []):
            values.add(t[2])
    return len(values)


def test_plain_zenoh_program_writes_a_triple_seen_by_tspace_query(server, space_name, run_tspace):
    proc = subprocess.run(
        [PYTHON, str(PROGRAMS / "plain_zenoh.py"), server.endpoint, space_name, "write"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert proc.returncode == 0, proc.stderr
    ack = json.loads(proc.stdout.splitlines()[0])
    assert ack["seq"] >= 1
    assert proc.stdout.splitlines()[-1] == "space not imported"
    result = run_tspace("query", "--template", "?b ac:battery_level ?l")
    assert result.returncode == 0, result.stderr
    assert 'ac:robot9_battery  "low"' in result.stdout


def test_plain_zenoh_program_watches_a_change_written_by_the_library(ts, server, space_name):
    watcher = program("plain_zenoh.py", server.endpoint, space_name, "watch", stdin=True)
    out = Lines(watcher)
    try:
        wait_for(lambda: "ready" in out.lines, 20, "the plain subscriber")
        ts.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))])
        ts.remove([(AC.robot1_battery, AC.battery_level, Literal("very low"))])
        key = f'tspace/{space_name}/t/ac:robot1_battery/ac:battery_level/"very low"'
        wait_for(lambda: f"- {key}" in out.lines, 20, "the delete sample")
        assert out.lines.index(f"+ {key}") < out.lines.index(f"- {key}")
    finally:
        assert watcher.stdin is not None
        watcher.stdin.close()
        assert watcher.wait(timeout=10) == 0
    assert out.lines[-1] == "space not imported"


def test_triples_reach_a_plain_subscriber_each_time_one_comes_back(ts, space_name):
    """The store publishes triple keys while someone subscribes, told so by Zenoh as
    subscribers come and go: a subscriber that comes back after none was there hears
    the next writes again."""
    for round_ in range(3):
        ts.write([(AC.probe, AC.round, Literal(f"nobody-{round_}"))])  # nobody listens yet
        _heard_while_subscribed(ts, space_name, str(round_))


def _heard_while_subscribed(ts, space_name: str, tag: str) -> None:
    """Subscribe to the triple keys, write until a write tagged `tag` is heard, leave."""
    heard: list[str] = []
    sub = ts.session.declare_subscriber(
        f"tspace/{space_name}/t/**", lambda sample: heard.append(str(sample.key_expr))
    )
    written = iter(range(1_000_000))

    def written_and_heard() -> bool:
        ts.write([(AC.probe, AC.round, Literal(f"{tag}-{next(written)}"))])
        return any(f'"{tag}-' in key for key in heard)

    try:
        wait_for(written_and_heard, 10, f"a triple heard in round {tag}")
    finally:
        sub.undeclare()
