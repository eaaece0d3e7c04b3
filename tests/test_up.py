"""`tspace up` runs a launch file's processes, restarts crashed ones and leaves nothing behind."""

from __future__ import annotations

import json
import re
import signal
import socket
import subprocess
import urllib.request
from pathlib import Path

import pytest
from hmipage import hmi_post
from rdflib import RDF, RDFS, Literal, URIRef
from uprun import Up, alive

from conftest import REPO, free_port, tspace_cmd, wait_for
from space import TripleSpace

LAUNCH = """
space = "ward"
robots = ["robot1"]
load = ["{repo}/ontology/selfconfig.ttl", "{repo}/ontology/robots/hospital.ttl"]

[supervisor]
grace = 3.0
backoff_initial = 0.5

[[agent]]
name = "hw_monitor"
per_robot = true

[[agent]]
name = "hmi"
"""


@pytest.fixture
def launch(tmp_path: Path) -> Path:
    path = tmp_path / "ward.toml"
    path.write_text(LAUNCH.format(repo=REPO))
    return path


def hmi_state(port: int) -> dict:
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=2) as reply:
        return json.load(reply)


def hmi_connected(port: int) -> bool:
    try:
        return hmi_state(port)["connected"]
    except OSError:
        return False


def test_up_shows_the_robot_and_sigint_stops_every_process(tmp_path, launch):
    with Up(tmp_path, launch) as up:
        up.wait_started()
        wait_for(lambda: up.stdout_has("robot1: task Idle, at dock1"), 20, "the robot in the log")
        wait_for(lambda: hmi_connected(up.hmi_port), 20, "the HMI page")
        assert up.stderr_has(f"HMI at http://127.0.0.1:{up.hmi_port}/")
        processes = up.track()
        assert len(processes) == 3, up.logs()  # serve, hw_monitor, hmi
        up.proc.send_signal(signal.SIGINT)
        assert up.proc.wait(timeout=15) == 0, up.logs()
        assert [p for p in processes if alive(p)] == []


def test_a_killed_agent_is_restarted_and_the_supervisor_says_so(tmp_path, launch):
    with Up(tmp_path, launch) as up:
        up.wait_started()
        first = wait_for(lambda: up.pid_of("agents.hw_monitor"), 10, "hw_monitor")
        wait_for(lambda: hmi_connected(up.hmi_port), 20, "the HMI page")
        # Killed only once connected, so that its restart is the second connection.
        log = up.data / "logs" / "hw_monitor.log"
        wait_for(lambda: "connected to space 'ward'" in log.read_text(), 20, "hw_monitor", up.logs)
        subprocess.run(["kill", "-9", str(first)], check=True)
        wait_for(
            lambda: up.stderr_has("hw_monitor: crashed (killed by SIGKILL); restarting in 0.5 s"),
            10,
            "the crash report",
        )
        wait_for(lambda: up.stderr_has("hw_monitor: restarted (pid "), 10, "the restart report")
        second = wait_for(lambda: up.pid_of("agents.hw_monitor"), 10, "the new hw_monitor")
        assert second != first
        # The new monitor connects and goes on reporting the robot's devices.
        wait_for(
            lambda: log.read_text().count("connected to space 'ward'") == 2,
            20,
            "the new hw_monitor to connect",
            up.logs,
        )


def test_sigterm_stops_every_process(tmp_path, launch):
    with Up(tmp_path, launch) as up:
        up.wait_started()
        processes = up.track()
        up.proc.send_signal(signal.SIGTERM)
        assert up.proc.wait(timeout=15) == 0, up.logs()
        assert [p for p in processes if alive(p)] == []


def test_ctrl_c_pressed_again_and_again_still_stops_every_process(tmp_path, launch):
    """An impatient operator: every interrupt after the first lands while up is stopping
    (the handler once took a lock the interrupted loop could hold, and up hung for good)."""
    with Up(tmp_path, launch) as up:
        up.wait_started()
        processes = up.track()
        for _ in range(20):
            up.proc.send_signal(signal.SIGINT)
        assert up.proc.wait(timeout=15) == 0, up.logs()
        assert [p for p in processes if alive(p)] == []


def test_a_killed_up_takes_its_processes_with_it(tmp_path, launch):
    with Up(tmp_path, launch) as up:
        up.wait_started()
        processes = up.track()
        assert len(processes) == 3
        up.proc.kill()
        up.proc.wait()
        wait_for(lambda: not any(alive(p) for p in processes), 10, "the orphans to die")


def test_up_resumes_the_space_and_fresh_starts_it_over(tmp_path, launch):
    robot = URIRef("https://w3id.org/tspace/selfconfig#robot1")
    note = (robot, RDFS.comment, Literal("left by the last run"))  # in no launch file

    def holds(up: Up, triple: tuple) -> bool:
        with TripleSpace.open(f"tcp/127.0.0.1:{up.port}", space="ward") as ts:
            return triple in ts.query(triple)

    with Up(tmp_path, launch) as up:
        up.wait_started()
        with TripleSpace.open(f"tcp/127.0.0.1:{up.port}", space="ward") as ts:
            ts.write([note])
        up.proc.send_signal(signal.SIGINT)
        assert up.proc.wait(timeout=15) == 0, up.logs()
    with Up(tmp_path, launch) as up:  # the same data folder: the space is kept
        up.wait_started()
        assert up.stderr_has("resuming from them (--fresh starts over)"), up.logs()
        assert holds(up, note)
        up.proc.send_signal(signal.SIGINT)
        assert up.proc.wait(timeout=15) == 0, up.logs()
    with Up(tmp_path, launch, "--fresh") as up:
        up.wait_started()
        assert up.stderr_has("started afresh"), up.logs()
        assert not holds(up, note)
        assert holds(up, (robot, RDF.type, URIRef("https://w3id.org/tspace/selfconfig#Robot")))


def test_a_broken_launch_file_is_reported_in_one_line(tmp_path):
    broken = tmp_path / "broken.toml"
    broken.write_text('space = "x"\n[[agent]]\nmodule = "agents.hmi"\n')
    result = subprocess.run(
        tspace_cmd("up", str(broken), "--data", str(tmp_path)),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        "tspace up: every [[agent]] needs a name: {'module': 'agents.hmi'}"
    ]


def test_a_missing_launch_file_is_reported_in_one_line(tmp_path):
    result = subprocess.run(
        tspace_cmd("up", "nosuch.toml", "--data", str(tmp_path)),
        capture_output=True,
        text=True,
        timeout=30,
        cwd=tmp_path,
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        "tspace up: cannot read launch file nosuch.toml: No such file or directory"
    ]


@pytest.mark.parametrize("named_by", ["--hmi-port", "the launch file"])
def test_a_taken_hmi_port_that_was_named_stops_up_at_once_in_one_line(tmp_path, launch, named_by):
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        port = holder.getsockname()[1]
        if named_by == "--hmi-port":
            extra = ["--hmi-port", str(port)]
            source = "--hmi-port"
        else:
            launch.write_text(launch.read_text() + f'args = ["--http-port", "{port}"]\n')
            extra = []
            source = "--http-port of agent hmi in the launch file"
        listen = f"tcp/127.0.0.1:{free_port()}"
        argv = tspace_cmd("up", str(launch), "--listen", listen, "--data", str(tmp_path / "data"))
        result = subprocess.run([*argv, *extra], capture_output=True, text=True, timeout=30)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        f"tspace up: HMI port {port} ({source}) is already in use on 127.0.0.1"
    ]
    assert not (tmp_path / "data" / "logs").exists()  # nothing was started


def test_up_outside_the_project_runs_the_hospital_and_moves_off_a_taken_default_port(tmp_path):
    """No launch file, run from elsewhere: the shipped hospital, its HMI on a free port."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    with socket.socket() as holder:
        try:
            holder.bind(("127.0.0.1", 8080))
            holder.listen()
        except OSError:
            pass  # something else holds 8080: taken all the same
        with Up(tmp_path, None, name_hmi_port=False, cwd=elsewhere) as up:
            up.wait_started()
            assert up.stderr_has("HMI port 8080 is already in use on 127.0.0.1; using "), up.logs()
            line = next(line for line in up.err if "HMI at http://127.0.0.1:" in line)
            port = int(re.search(r"127\.0\.0\.1:(\d+)/", line).group(1))
            assert port != 8080
            wait_for(lambda: "robot1" in robots_shown(port), 30, "the HMI page", up.logs)
            up.wait_connected("reasoner", "hw_monitor", "nav_monitor", "behavior")
            assert up.stdout_has("robot1: task Idle, at dock1"), up.logs()
            up.proc.send_signal(signal.SIGINT)
            assert up.proc.wait(timeout=30) == 0, up.logs()


def post(port: int, path: str, body: dict) -> dict:
    status, answer = hmi_post(port, path, body)
    assert status == 200, answer
    return answer


def robots_shown(port: int) -> dict[str, dict]:
    try:
        return {r["name"]: r for r in hmi_state(port)["robots"]}
    except OSError:
        return {}


@pytest.mark.parametrize("reasoners", ["one for the fleet", "one per robot"])
def test_the_fleet_launch_file_commands_only_the_robot_whose_battery_is_low(tmp_path, reasoners):
    """deploy/fleet.toml as shipped, and with its documented per-robot reasoner variant."""
    text = (REPO / "deploy" / "fleet.toml").read_text().replace('"../', f'"{REPO}/')
    if reasoners == "one per robot":
        reasoner = '[[agent]]\nname = "reasoner"\nargs = ['
        assert reasoner in text
        text = text.replace(
            reasoner, '[[agent]]\nname = "reasoner"\nper_robot = true\nargs = ["--per-robot", '
        )
    launch = tmp_path / "fleet.toml"
    launch.write_text(text)
    with Up(tmp_path, launch) as up:
        up.wait_started()
        names = {"robot1", "robot2", "guide1"}
        wait_for(lambda: set(robots_shown(up.hmi_port)) == names, 30, "the HMI showing the fleet")
        # Every robot's devices are active before the battery of one of them runs low.
        wait_for(
            lambda: all(
                d["mode"] == "active"
                for r in robots_shown(up.hmi_port).values()
                for d in r["devices"]
            ),
            30,
            "every device active",
        )
        post(up.hmi_port, "/api/battery", {"robot": "robot2", "level": "very low"})

        def robot2_heading_to_dock() -> dict | None:
            robots = robots_shown(up.hmi_port)
            robot2 = robots.get("robot2", {})
            return (
                robots
                if robot2.get("task_type") == "GoingToDock" and robot2.get("speed") == "low"
                else None
            )

        robots = wait_for(robot2_heading_to_dock, 30, "robot2 heading to a dock at low speed")
        for other in ("robot1", "guide1"):
            assert robots[other]["task_type"] == "Idle", robots[other]
            assert robots[other]["speed"] == "normal", robots[other]
        expected = 13 if reasoners == "one for the fleet" else 15  # serve + agents
        assert len(up.track()) == expected, up.logs()
        up.proc.send_signal(signal.SIGINT)
        assert up.proc.wait(timeout=30) == 0, up.logs()
