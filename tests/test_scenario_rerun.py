"""`tspace up --scenario battery` reruns: after Ctrl-C or kill -9 at any step, and after completing.

One data directory for the whole test, as a user's default one: each run starts
the scenario from its own initial state, whatever the last run left. Run k is
stopped once step k is done (Ctrl-C, or kill -9 of `tspace up` itself every
third time), so the next run must start over and pass steps 1 to k+1 again; a
final `--once` run completes after the interrupt at step 9, another after a
completed run, and a plain `tspace up` then resumes the robot, idle.
"""

from __future__ import annotations

import json
import signal
import urllib.request

import pytest
from test_scenario_battery import HOSPITAL, STEPS, completed_steps, needs_reasoner
from uprun import Up, alive

from conftest import wait_for


def gone(up: Up) -> bool:
    return not any(alive(pid) for pid in up.seen)


@needs_reasoner
@pytest.mark.timeout(900)  # eleven runs of tspace up: minutes on a busy machine
def test_the_scenario_reruns_after_an_interrupt_at_every_step(tmp_path):
    for step in range(1, len(STEPS) + 1):
        with Up(tmp_path, HOSPITAL, "--scenario", "battery") as up:
            wait_for(
                lambda up=up, step=step: len(completed_steps(up)) >= step or up.proc.poll(),
                120,
                f"step {step} of run {step}",
                up.logs,
            )
            assert completed_steps(up)[:step] == STEPS[:step], up.logs()
            if step == 1:
                assert up.stderr_has("started afresh") is False  # the first run: an empty space
            else:
                assert up.stderr_has("started afresh"), up.logs()
            up.track()
            if step % 3 == 0:
                up.proc.kill()
                assert up.proc.wait(timeout=10) == -signal.SIGKILL
            else:
                up.proc.send_signal(signal.SIGINT)
                assert up.proc.wait(timeout=30) == 0, up.logs()
            # Its processes go with it, even after kill -9 (they die with their parent).
            wait_for(lambda up=up: gone(up), 15, "the processes of the stopped run")

    for run in ("after the interrupt at step 9", "after a completed run"):
        with Up(tmp_path, HOSPITAL, "--scenario", "battery", "--once") as up:
            assert up.proc.wait(timeout=9 * 90) == 0, f"{run}:\n{up.logs()}"
            assert completed_steps(up) == STEPS, up.logs()

    # Without --scenario or --fresh the space is kept: the robot resumes, and idles (the
    # scenario ended the patient's visit) instead of overrunning and postponing it forever.
    with Up(tmp_path, HOSPITAL) as up:
        wait_for(lambda: up.stderr_has("resuming from them"), 30, "the resume", up.logs)
        wait_for(lambda: up.stdout_has("robot1: task Idle"), 30, "the robot to idle", up.logs)
        assert not up.stderr_has("started afresh")
        # The HMI rebuilt the robot's history from the store's log: the last run, after the
        # reset that started it (the page starts the robot's history again there).
        url = f"http://127.0.0.1:{up.hmi_port}/api/history"

        def history_read() -> bool:
            try:
                with urllib.request.urlopen(url, timeout=5) as reply:
                    return b'"firing"' in reply.read()
            except OSError:
                return False  # the HMI is still starting

        wait_for(history_read, 60, "the HMI's history", up.logs)
        with urllib.request.urlopen(url, timeout=5) as reply:
            kinds = [e["kind"] for e in json.load(reply) if e["robot"] == "robot1"]
        last_run = kinds[len(kinds) - kinds[::-1].index("reset") :]
        assert {"battery", "task", "firing"} <= set(last_run), last_run
