"""The HMI page in a real headless Chromium: live robot state, assigning a task, the battery.

Chromium is driven over the Chrome DevTools protocol (websocket-client), clicks
are real mouse events at the buttons' positions. Needs Debian's `chromium`.
"""

from __future__ import annotations

import itertools
import json
import shutil
import subprocess
import time
import urllib.request
from pathlib import Path

import pytest
from agentprocs import value
from rdflib import Literal, Namespace
from uprun import Up

from conftest import AC_NS, REPO, wait_for
from space import TripleSpace

websocket = pytest.importorskip("websocket", reason="the browser test needs websocket-client")

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="needs a Chromium binary (Debian: apt-get install chromium)"
)

LAUNCH = """
space = "ward"
robots = ["robot1"]
load = ["{repo}/ontology/selfconfig.ttl", "{repo}/ontology/robots/hospital.ttl"]

[[agent]]
name = "reasoner"
args = ["--rules", "{repo}/rules/selfconfig.rules"]

[[agent]]
name = "hw_monitor"
per_robot = true

[[agent]]
name = "nav_monitor"
per_robot = true

[[agent]]
name = "behavior"
per_robot = true

[[agent]]
name = "hmi"
"""


class Browser:
    """A headless Chromium with one page, driven through the DevTools protocol."""

    def __init__(self, profile: Path, url: str) -> None:
        assert CHROMIUM is not None
        self.proc = subprocess.Popen(
            [
                CHROMIUM,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--remote-debugging-port=0",
                "--remote-allow-origins=*",
                f"--user-data-dir={profile}",
                url,
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        self._ids = itertools.count(1)
        port_file = profile / "DevToolsActivePort"
        wait_for(lambda: port_file.is_file() and port_file.read_text().strip(), 30, "Chromium")
        port = int(port_file.read_text().split()[0])
        page = wait_for(lambda: self._page(port), 10, "Chromium's page")
        self.ws = websocket.create_connection(page, timeout=10, suppress_origin=True)

    @staticmethod
    def _page(port: int) -> str | None:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=2) as reply:
            targets = json.load(reply)
        return next((t["webSocketDebuggerUrl"] for t in targets if t["type"] == "page"), None)

    def close(self) -> None:
        if hasattr(self, "ws"):
            self.ws.close()
        self.proc.kill()
        self.proc.wait()

    def call(self, method: str, **params: object) -> dict:
        """Send one DevTools command and return its result (events in between are skipped)."""
        ident = next(self._ids)
        self.ws.send(json.dumps({"id": ident, "method": method, "params": params}))
        while True:
            message = json.loads(self.ws.recv())
            if message.get("id") == ident:
                assert "error" not in message, message
                return message["result"]

    def js(self, expression: str) -> object:
        """Evaluate JavaScript in the page and return its value."""
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        assert "exceptionDetails" not in result, result
        return result["result"].get("value")

    def text(self, selector: str) -> str | None:
        """Return the text of the first element matching `selector`, or None."""
        return self.js(f"document.querySelector({json.dumps(selector)})?.textContent ?? null")

    def choose(self, selector: str, value: str) -> None:
        """Pick an option of a <select>, as a person would."""
        found = self.js(
            f"""(() => {{
                const s = document.querySelector({json.dumps(selector)});
                if (!s || ![...s.options].some(o => o.value === {json.dumps(value)})) return false;
                s.value = {json.dumps(value)};
                s.dispatchEvent(new Event('change', {{bubbles: true}}));
                return true; }})()"""
        )
        assert found, f"no option {value!r} in {selector}"

    def click(self, selector: str) -> None:
        """Click the middle of an element with the mouse."""
        box = self.js(
            f"""(() => {{ const e = document.querySelector({json.dumps(selector)});
                e.scrollIntoView({{block: 'center'}});
                const r = e.getBoundingClientRect();
                return [r.x + r.width / 2, r.y + r.height / 2]; }})()"""
        )
        x, y = box
        for kind in ("mousePressed", "mouseReleased"):
            self.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left", clickCount=1)


@pytest.fixture
def deployment(tmp_path):
    launch = tmp_path / "ward.toml"
    launch.write_text(LAUNCH.format(repo=REPO))
    with Up(tmp_path, launch) as up:
        up.wait_started()
        # A battery set from the page before the reasoner listens is reasoned at its load,
        # with no change to name as the cause.
        up.wait_connected("reasoner", "hw_monitor", "nav_monitor", "behavior", "hmi")
        yield up


@pytest.fixture
def page(tmp_path, deployment):
    browser = Browser(tmp_path / "chromium", f"http://127.0.0.1:{deployment.hmi_port}/")
    try:
        yield browser
    finally:
        browser.close()


ROBOT = '[data-robot="robot1"]'
AC = Namespace(AC_NS)


def test_the_page_shows_the_robot_live_and_assigns_a_task(page, deployment):
    wait_for(lambda: page.text("#status") == "live", 30, "the page to go live")
    wait_for(lambda: page.text(f"{ROBOT} [data-field=task_type]") == "Idle", 30, "the robot")
    assert page.text(f"{ROBOT} [data-field=location]") == "dock1"
    assert page.text(f"{ROBOT} [data-field=speed]") == "normal"
    assert page.text(f'{ROBOT} tr[data-device="robot1_screen"] [data-field=mode]') == "active"
    assert page.text(f"{ROBOT} [data-field=battery]").startswith("normal (")

    page.choose(f"{ROBOT} .task-select", "AttendingPatient")
    page.choose(f"{ROBOT} .person-select", "patient_ane")
    page.click(f"{ROBOT} .assign-task")
    wait_for(
        lambda: page.text(f"{ROBOT} [data-field=task_type]") == "AttendingPatient",
        30,
        "the new task to arrive on the page",
    )
    # The page may show the task (pushed by the space) before the POST's answer arrives.
    wait_for(lambda: page.text(f"{ROBOT} .feedback") == "done", 10, "the HMI to confirm")
    # The robot sets off: the navigation monitor moves it away from the dock.
    wait_for(
        lambda: page.text(f"{ROBOT} [data-field=location]") != "dock1",
        30,
        "the robot to leave the dock",
    )


def test_a_very_low_battery_set_from_the_page_fires_the_papers_rules(page, deployment):
    wait_for(lambda: page.text("#status") == "live", 30, "the page to go live")
    wait_for(lambda: page.text(f"{ROBOT} [data-field=task_type]") == "Idle", 30, "the robot")
    page.choose(f"{ROBOT} .battery-select", "very low")
    started = time.monotonic()
    page.click(f"{ROBOT} .set-battery")

    def firings() -> list[str]:
        return page.js("[...document.querySelectorAll('#firings li')].map(li => li.textContent)")

    def fired(text: str) -> bool:
        return any(text in f and "very low" in f for f in firings())

    wait_for(lambda: fired("ac:robot1_base ac:motion_speed low"), 30, "the low speed rule")
    wait_for(lambda: fired("ac:robot1 ac:current_task ac:task_going_to_dock"), 30, "go to dock")
    wait_for(lambda: fired("ac:robot1_screen ac:running_mode stand-by"), 30, "stand-by rule")
    assert time.monotonic() - started < 30
    line = next(f for f in firings() if "ac:motion_speed low" in f)
    assert " <- " in line or " ← " in line, line  # the cause is shown


def test_a_battery_level_set_from_the_page_holds_and_the_robot_acts_on_it(page, deployment):
    wait_for(lambda: page.text("#status") == "live", 30, "the page to go live")
    wait_for(lambda: page.text(f"{ROBOT} [data-field=task_type]") == "Idle", 30, "the robot")
    page.choose(f"{ROBOT} .battery-select", "low")
    page.click(f"{ROBOT} .set-battery")
    # Nobody is served and the battery is low: the interaction devices go to stand-by.
    for device in ("robot1_screen", "robot1_speakers", "robot1_microphone"):
        mode = f'{ROBOT} tr[data-device="{device}"] [data-field=mode]'
        wait_for(lambda mode=mode: page.text(mode) == "stand-by", 30, f"{device} on stand-by")
    # Once the simulated drivers obeyed, the hw_monitor has reported since the level was set:
    # the level is still the one set from the page.
    with TripleSpace.open(f"tcp/127.0.0.1:{deployment.port}", space="ward") as ts:
        wait_for(
            lambda: value(ts, AC.robot1_screen, AC.actual_mode) == Literal("stand-by"),
            30,
            "the screen's driver to switch",
        )
    assert page.text(f"{ROBOT} [data-field=battery]").startswith("low ("), page.text("#robots")
    assert page.text(f'{ROBOT} tr[data-device="robot1_screen"] [data-field=mode]') == "stand-by"
