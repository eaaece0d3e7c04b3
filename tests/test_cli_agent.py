"""`tspace agent NAME`: every agent module that runs as a process can be run by name."""

from __future__ import annotations

import json
import signal
import subprocess
import urllib.request

from agentprocs import AgentProcess, knowledge

from conftest import free_port, tspace_cmd, wait_for

PROCESSES = {
    "behavior",
    "crew",
    "fleet_monitor",
    "hmi",
    "hw_monitor",
    "nav_monitor",
    "reasoner",
    "ros2",
}


def test_every_agent_process_is_a_choice_and_answers_help():
    listed = subprocess.run(tspace_cmd("agent", "--help"), capture_output=True, text=True)
    assert listed.returncode == 0, listed.stderr
    for name in PROCESSES:
        assert name in listed.stdout
        shown = subprocess.run(
            tspace_cmd("agent", name, "--help"), capture_output=True, text=True, timeout=60
        )
        assert shown.returncode == 0, (name, shown.stderr)
        assert shown.stdout.startswith(f"usage: tspace agent {name} "), shown.stdout
        assert "python -m" not in shown.stdout
    unknown = subprocess.run(tspace_cmd("agent", "view"), capture_output=True, text=True)
    assert unknown.returncode == 2
    assert "invalid choice: 'view'" in unknown.stderr


def robots_on_page(port: int) -> list[str]:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=2) as reply:
            return [r["name"] for r in json.load(reply)["robots"]]
    except OSError:
        return []


def test_tspace_agent_hmi_serves_the_page(ts, server, space_name, launch, tmp_path):
    ts.write(knowledge())
    port = free_port()
    proc = AgentProcess("hmi", server.endpoint, space_name, tmp_path, "--http-port", str(port))
    proc.argv = tspace_cmd("agent", "hmi", *proc.argv[3:])
    launch.procs.append(proc.start())
    wait_for(lambda: robots_on_page(port) == ["robot1"], 30, "the HMI page", proc.logs)
    assert proc.stop(signal.SIGINT) == 0, proc.logs()
