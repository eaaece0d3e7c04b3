"""The supervisor restarts crashed children with back-off and leaves nothing behind."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from agents.runtime.supervisor import ProcessSpec, Supervisor

SLEEPER = (sys.executable, "-c", "import time; time.sleep(60)")


def wait_for(condition, timeout: float = 10.0, what: str = "condition") -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return False
    return state != "Z"


@pytest.fixture
def events():
    return []


@pytest.fixture
def supervisor(tmp_path, events):
    sup = Supervisor(
        log_dir=tmp_path / "logs", on_event=events.append, grace=1.0, backoff=(0.1, 0.4)
    )
    try:
        yield sup
    finally:
        sup.stop()


def test_a_killed_child_is_restarted_and_the_restart_is_announced(supervisor, events):
    first = supervisor.start(ProcessSpec("worker", SLEEPER))
    os.kill(first, signal.SIGKILL)

    def restarted() -> bool:
        supervisor.poll()
        return supervisor.pid("worker") not in (None, first)

    wait_for(restarted, what="restart")
    assert "worker: crashed (killed by SIGKILL); restarting in 0.1 s" in events
    assert any(e.startswith("worker: restarted (pid ") for e in events)
    assert alive(supervisor.pid("worker"))
    assert supervisor.status()[0].restarts == 1


def test_back_off_doubles_for_a_crash_loop_up_to_the_longest_delay(supervisor, events):
    supervisor.start(ProcessSpec("crasher", (sys.executable, "-c", "raise SystemExit(3)")))

    def crashed_four_times() -> bool:
        supervisor.poll()
        return sum("crashed" in e for e in events) >= 4

    wait_for(crashed_four_times, what="four crashes")
    delays = [e.rsplit("in ", 1)[1] for e in events if "crashed" in e]
    assert delays[:4] == ["0.1 s", "0.2 s", "0.4 s", "0.4 s"]
    assert "crasher: crashed (exit code 3); restarting in 0.1 s" in events


def test_a_child_that_finishes_cleanly_is_not_restarted(supervisor, events):
    supervisor.start(ProcessSpec("oneshot", (sys.executable, "-c", "pass")))

    def stopped() -> bool:
        supervisor.poll()
        return "oneshot: stopped (exit code 0)" in events

    wait_for(stopped, what="clean exit")
    supervisor.poll()
    assert supervisor.pid("oneshot") is None
    assert not any("restart" in e for e in events)


def test_stop_kills_a_child_that_ignores_sigterm_and_what_it_spawned(supervisor, tmp_path, events):
    script = textwrap.dedent(
        """
        import signal, subprocess, sys, time
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        grandchild = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
        print(grandchild.pid, flush=True)
        time.sleep(60)
        """
    )
    pid = supervisor.start(ProcessSpec("stubborn", (sys.executable, "-c", script)))
    log = supervisor.log_path("stubborn")
    wait_for(lambda: log.read_text().strip() != "", what="grandchild pid")
    grandchild = int(log.read_text().split()[0])
    started = time.monotonic()
    supervisor.stop()
    assert time.monotonic() - started >= 1.0
    assert "stubborn: did not stop in 1 s, killing" in events
    wait_for(lambda: not alive(pid) and not alive(grandchild), what="process group gone")


def test_children_die_with_a_supervisor_killed_by_sigkill(tmp_path):
    script = textwrap.dedent(
        f"""
        import sys, time
        from pathlib import Path
        from agents.runtime.supervisor import ProcessSpec, Supervisor
        sup = Supervisor(log_dir=Path({str(tmp_path)!r}), on_event=print)
        print(sup.start(ProcessSpec("orphan", {SLEEPER!r})), flush=True)
        time.sleep(60)
        """
    )
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    child = None
    try:
        assert parent.stdout is not None
        child = int(parent.stdout.readline())
        assert alive(child)
        parent.kill()
        parent.wait()
        wait_for(lambda: not alive(child), what="orphan to die")
    finally:
        parent.kill()
        parent.wait()
        if child is not None and alive(child):
            os.kill(child, signal.SIGKILL)
