"""What `tspace up` and the HMI show of the space: bad values survived, firings readable."""

from __future__ import annotations

import json
import re
import urllib.request
from pathlib import Path

from rdflib import Literal, Namespace
from uprun import Up

from conftest import AC_NS, REPO, wait_for
from space import TripleSpace

AC = Namespace(AC_NS)

LAUNCH = """
space = "ward"
robots = ["robot1"]
load = ["{repo}/ontology/selfconfig.ttl", "{repo}/ontology/robots/hospital.ttl"]
{agents}
[[agent]]
name = "hmi"
"""
REASONER = """
[[agent]]
name = "reasoner"
args = ["--rules", "{repo}/rules/selfconfig.rules"]
"""


def launch_file(tmp_path: Path, agents: str = "") -> Path:
    path = tmp_path / "ward.toml"
    path.write_text(LAUNCH.format(repo=REPO, agents=agents.format(repo=REPO)))
    return path


def hmi_state(port: int) -> dict:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=2) as reply:
            return json.load(reply)
    except OSError:
        return {}


def battery_shown(port: int) -> tuple[str, int | None] | None:
    robots = hmi_state(port).get("robots", [])
    return (robots[0]["battery"], robots[0]["charge"]) if robots else None


def test_a_charge_that_is_not_a_number_is_shown_as_unknown_and_reported_once(tmp_path):
    with Up(tmp_path, launch_file(tmp_path)) as up:
        up.wait_started()
        up.wait_connected("hmi")
        wait_for(lambda: up.stdout_has("battery normal (80%)"), 20, "the robot in the view")
        with TripleSpace.open(f"tcp/127.0.0.1:{up.port}", space="ward") as ts:
            ts.write([(AC.robot1_battery, AC.charge_percent, Literal("abc"))])
            wait_for(lambda: battery_shown(up.hmi_port) == ("normal", None), 10, "unknown charge")
            ts.write([(AC.robot1_battery, AC.battery_level, Literal("low"))])
            wait_for(lambda: battery_shown(up.hmi_port) == ("low", None), 10, "the next change")
            wait_for(lambda: up.stdout_has("robot1: task Idle, at dock1, battery low, "), 10)
            ts.write([(AC.robot1_battery, AC.charge_percent, Literal(40))])
            wait_for(lambda: battery_shown(up.hmi_port) == ("low", 40), 10, "a good charge again")
            wait_for(lambda: up.stdout_has("battery low (40%)"), 10, "the view", up.logs)
        assert up.proc.poll() is None, up.logs()
        warning = "ac:robot1_battery ac:charge_percent 'abc' is not a percentage; shown as unknown"
        assert sum(warning in line for line in up.err) == 1, up.logs()
        hmi_log = (up.data / "logs" / "hmi.log").read_text()
        assert hmi_log.count(warning) == 1, hmi_log
        assert "Traceback" not in hmi_log
        assert not up.stderr_has("hmi: crashed"), up.logs()


PREFIXED = re.compile(r"^(ac|rdf|rdfs|owl|xsd):\S+$")


def readable(line: str) -> bool:
    """Return True if a firing's triple has prefixed names and no blank node."""
    s, p, o = line.split(" ", 2)
    return bool(PREFIXED.match(s) and PREFIXED.match(p)) and (
        p != "rdf:type" or bool(PREFIXED.match(o))
    )


def test_firing_lines_use_prefixed_names_and_leave_anonymous_classes_out(tmp_path):
    with Up(tmp_path, launch_file(tmp_path, REASONER), "--raw-firings") as up:
        up.wait_started()
        up.wait_connected("reasoner", "hmi")
        with TripleSpace.open(f"tcp/127.0.0.1:{up.port}", space="ward") as ts:
            ts.write([(AC.robot1_battery, AC.battery_level, Literal("very low"))])

        def standby_firing() -> dict | None:
            firings = hmi_state(up.hmi_port).get("firings", [])
            return next((f for f in firings if "ac:StandbyDevice" in " ".join(f["added"])), None)

        firing = wait_for(standby_firing, 20, "the stand-by firing on the page", up.logs)
        assert "ac:robot1_screen rdf:type ac:StandbyDevice" in firing["added"]
        assert "ac:robot1_base ac:motion_speed low" in firing["added"]
        assert all(readable(line) for line in firing["added"]), firing
        assert firing["cause"] == ["ac:robot1_battery ac:battery_level very low"]
        wait_for(lambda: up.stdout_has("rdf:type ac:StandbyDevice"), 10, "the firing line")
        lines = [line for line in up.out if line.startswith("firing: ")]
        assert lines and not any("http://" in line for line in lines), lines
