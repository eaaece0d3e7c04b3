"""The fleet of deploy/fleet.toml in secure mode: every process its own certificate.

`tspace up --secure`: mutual TLS on every link, the router enforcing the
policy of deploy/policy.toml, the store checking every write. The fleet works
as it does in the open, and what the policy forbids (the HMI setting a
battery) is refused and logged.
"""

from __future__ import annotations

import json
import signal
import subprocess
import urllib.error
import urllib.request

import pytest
from hmipage import hmi_post
from rdflib import Literal, Namespace
from uprun import Up

from conftest import AC_NS, REPO, tspace_cmd, wait_for
from space import TripleSpace, load_identity
from space.presence import alive_agents

AC = Namespace(AC_NS)


def robots_shown(port: int) -> dict[str, dict]:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=5) as reply:
            return {r["name"]: r for r in json.load(reply)["robots"]}
    except OSError:
        return {}


def post(port: int, path: str, body: dict) -> int:
    """POST to the HMI as its page does; return the HTTP status."""
    return hmi_post(port, path, body)[0]


@pytest.mark.parametrize("reasoners", ["one for the fleet", "one per robot"])
def test_the_fleet_works_in_secure_mode_and_the_hmi_cannot_set_a_battery(tmp_path, reasoners):
    certs = tmp_path / "certs"
    fleet = tmp_path / "fleet.toml"
    text = (REPO / "deploy" / "fleet.toml").read_text().replace('"../', f'"{REPO}/')
    if reasoners == "one per robot":  # the variant deploy/fleet.toml documents
        reasoner = '[[agent]]\nname = "reasoner"\nargs = ['
        assert reasoner in text
        text = text.replace(
            reasoner, '[[agent]]\nname = "reasoner"\nper_robot = true\nargs = ["--per-robot", '
        )
    fleet.write_text(text)
    init = tspace_cmd("certs", "init", str(certs), "--fleet", str(fleet))
    assert subprocess.run(init, capture_output=True, timeout=60).returncode == 0
    with Up(tmp_path, fleet, "--secure", str(certs), scheme="tls") as up:
        up.wait_started()
        names = {"robot1", "robot2", "guide1"}
        wait_for(lambda: set(robots_shown(up.hmi_port)) == names, 60, "the fleet", up.logs)
        wait_for(
            lambda: all(
                d["mode"] == "active"
                for r in robots_shown(up.hmi_port).values()
                for d in r["devices"]
            ),
            60,
            "every device active",
            up.logs,
        )
        # The HMI writes task requests only: its battery button is refused, and logged.
        assert post(up.hmi_port, "/api/battery", {"robot": "robot2", "level": "very low"}) >= 400
        serve_log = up.data / "logs" / "serve.log"
        wait_for(
            lambda: "refused hmi: may not write ac:battery_level" in serve_log.read_text(),
            10,
            "the store's refusal naming the HMI",
            up.logs,
        )
        assert robots_shown(up.hmi_port)["robot2"]["task_type"] == "Idle"
        # An operator at a console may: robot2 (only) goes to charge.
        identity = load_identity(certs, "operator")
        endpoint = f"tls/127.0.0.1:{up.port}"
        with TripleSpace.open(endpoint, space="fleet", identity=identity) as ts:
            # Every agent's liveliness token got through under its identity; so robots are present.
            kinds = ["hw_monitor", "nav_monitor", "behavior"]
            agents = {"fleet_monitor", "hmi"} | {f"{k}.{r}" for k in kinds for r in names}
            if reasoners == "one per robot":
                agents |= {f"reasoner.{robot}" for robot in names}
            else:
                agents.add("reasoner")
            wait_for(lambda: set(alive_agents(ts.session, "fleet")) == agents, 30, "every agent")
            wait_for(
                lambda: (
                    {s for s, _p, _o in ts.query((None, AC.presence, Literal("present")))}
                    == {AC[r] for r in names}
                ),
                30,
                "every robot present",
                up.logs,
            )
            battery = AC.robot2_battery
            ts.write(
                [
                    (battery, AC.battery_level, Literal("very low")),
                    (battery, AC.charge_percent, Literal(5)),
                ]
            )

        def robot2_heading_to_dock() -> dict | None:
            robots = robots_shown(up.hmi_port)
            robot2 = robots.get("robot2", {})
            heading = robot2.get("task_type") == "GoingToDock" and robot2.get("speed") == "low"
            return robots if heading else None

        robots = wait_for(robot2_heading_to_dock, 60, "robot2 heading to a dock", up.logs)
        # The reasoner may answer `why` (its one queryable): the low speed, down to the battery.
        with TripleSpace.open(endpoint, space="fleet", identity=identity) as ts:
            explained = ts.why((AC.robot2_base, AC.motion_speed, Literal("low")))
        assert explained, "no explanation of robot2's low speed"
        facts = {node.triple for e in explained for _depth, node in e.walk()}
        assert (AC.robot2_battery, AC.battery_level, Literal("very low")) in facts, explained
        for other in ("robot1", "guide1"):
            assert robots[other]["task_type"] == "Idle", robots[other]
        logs = "\n".join(p.read_text() for p in (up.data / "logs").glob("*.log"))
        refused = [line for line in logs.splitlines() if "refused" in line]
        assert all("refused hmi:" in line for line in refused), refused  # no agent else
        up.proc.send_signal(signal.SIGINT)
        assert up.proc.wait(timeout=30) == 0, up.logs()


def test_secure_up_names_a_missing_certificate_before_starting_anything(tmp_path):
    certs = tmp_path / "certs"
    init = tspace_cmd("certs", "init", str(certs), "--fleet", str(REPO / "deploy/hospital.toml"))
    assert subprocess.run(init, capture_output=True, timeout=60).returncode == 0
    (certs / "behavior.robot1.key").unlink()
    up = tspace_cmd(
        "up",
        str(REPO / "deploy/hospital.toml"),
        "--secure",
        str(certs),
        "--data",
        str(tmp_path / "data"),
    )
    done = subprocess.run(up, capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    assert "no identity 'behavior.robot1'" in done.stderr and "missing behavior.robot1.key" in (
        done.stderr
    )
    assert not (tmp_path / "data").exists()
