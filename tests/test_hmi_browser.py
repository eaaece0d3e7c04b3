"""The HMI page in a real headless Chromium: live state, tasks, the battery, plots, why, safety.

Chromium is driven over the Chrome DevTools protocol (websocket-client), clicks
are real mouse events at the buttons' positions. Needs Debian's `chromium`.
Screenshots of the scenario at 1024 and 1920 px go to bench/out/ (for the docs).
"""

from __future__ import annotations

import base64
import contextlib
import itertools
import json
import os
import shutil
import signal
import socket
import subprocess
import time
import urllib.error
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
        try:
            port_file = profile / "DevToolsActivePort"
            wait_for(lambda: port_file.is_file() and port_file.read_text().strip(), 30, "Chromium")
            port = int(port_file.read_text().split()[0])
            page = wait_for(lambda: self._page(port), 30, "Chromium's page")
            self.ws = websocket.create_connection(page, timeout=10, suppress_origin=True)
        except BaseException:
            self.close()  # a browser that never answered is still a process group to end
            raise

    @staticmethod
    def _page(port: int) -> str | None:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=2) as reply:
                targets = json.load(reply)
        except OSError:
            return None  # Chromium still starting (slow on a loaded machine): asked again

        return next((t["webSocketDebuggerUrl"] for t in targets if t["type"] == "page"), None)

    def close(self) -> None:
        try:
            if hasattr(self, "ws"):
                self.ws.close()
        finally:
            # Chromium's renderer and zygote processes share its session: end them all.
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.proc.pid, signal.SIGKILL)
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

    def navigate(self, url: str) -> None:
        """Load a page and wait until its document is complete."""
        self.call("Page.navigate", url=url)
        wait_for(lambda: self.js("document.readyState") == "complete", 20, f"{url} to load")

    def screenshot(self, path: Path, width: int) -> None:
        """Lay the page out `width` px wide and save the whole page as a PNG."""
        self.call(
            "Emulation.setDeviceMetricsOverride",
            width=width,
            height=900,
            deviceScaleFactor=1,
            mobile=False,
        )
        # Wait for the relayout: the charts follow their boxes' new width.
        wait_for(
            lambda: self.js(
                "[...document.querySelectorAll('.chart')].every(c => "
                "Math.abs(c.querySelector('.uplot').offsetWidth - c.clientWidth) < 40)"
            ),
            10,
            f"the charts at {width} px",
        )
        height = self.js("Math.ceil(document.documentElement.scrollHeight)")
        self.call(
            "Emulation.setDeviceMetricsOverride",
            width=width,
            height=height,
            deviceScaleFactor=1,
            mobile=False,
        )
        shot = self.call("Page.captureScreenshot", format="png")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(base64.b64decode(shot["data"]))

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


def firing_texts(page: Browser) -> list[str]:
    """Return the robot's firings as the page lists them: sentence, then the raw triples."""
    return page.js(
        f"[...document.querySelectorAll('{ROBOT} .firings li')].map(li => "
        "li.querySelector('.sentence').textContent + ' | ' + li.querySelector('pre').textContent)"
    )


def test_a_very_low_battery_set_from_the_page_fires_the_papers_rules(page, deployment):
    wait_for(lambda: page.text("#status") == "live", 30, "the page to go live")
    wait_for(lambda: page.text(f"{ROBOT} [data-field=task_type]") == "Idle", 30, "the robot")
    page.choose(f"{ROBOT} .battery-select", "very low")
    started = time.monotonic()
    page.click(f"{ROBOT} .set-battery")

    def fired(sentence: str, triple: str) -> bool:
        return any(sentence in f and triple in f for f in firing_texts(page))

    # Each firing reads as a sentence; its triples are there on demand, with its rules and cause.
    sentence = "battery very low → robot1 goes to the dock"
    wait_for(lambda: fired(sentence, "ac:robot1 ac:current_task ac:task_going_to_dock"), 30)
    wait_for(lambda: fired("at low speed", 'ac:robot1_base ac:motion_speed "low"'), 30)
    assert time.monotonic() - started < 30
    line = next(f for f in firing_texts(page) if '+ ac:robot1_base ac:motion_speed "low"' in f)
    assert "verylow_battery_causes_low_speed_existing" in line and " ← hmi" in line, line


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


def chart_values(page: Browser, series: int) -> list[float]:
    """Return the values of one series of the robot's chart (1: battery %, 2: speed)."""
    return page.js(
        f"(() => {{ const c = [...document.querySelectorAll('{ROBOT} .chart')][0]; "
        f"const u = c && c.querySelector('.uplot') && window.__charts?.get('robot1'); "
        f"return u ? u.data[{series}].filter(v => v !== null) : []; }})()"
    )


def task_spans(page: Browser) -> list[str]:
    """Return the task values laid on the robot's timeline, oldest first."""
    return page.js(
        f"[...document.querySelectorAll('{ROBOT} .lane.task .span')].map(s => s.textContent)"
    )


def test_the_scenario_through_the_page_plots_the_battery_and_the_docking(page, deployment):
    """Send the robot to a patient, drain its battery from the page: plot, timeline, why."""
    wait_for(lambda: page.text("#status") == "live", 30, "the page to go live")
    wait_for(lambda: page.text(f"{ROBOT} [data-field=task_type]") == "Idle", 30, "the robot")
    # The battery control starts at the battery's level, not at the lowest one.
    assert page.js(f"document.querySelector('{ROBOT} .battery-select').value") == "normal"
    page.choose(f"{ROBOT} .task-select", "AttendingPatient")
    page.choose(f"{ROBOT} .person-select", "patient_ane")
    page.click(f"{ROBOT} .assign-task")
    wait_for(lambda: page.text(f"{ROBOT} [data-field=location]") != "dock1", 30, "leaving")
    page.choose(f"{ROBOT} .battery-select", "very low")
    page.click(f"{ROBOT} .set-battery")
    wait_for(lambda: "GoingToDock" in task_spans(page), 30, "going to the dock on the timeline")
    wait_for(
        lambda: page.text(f"{ROBOT} [data-field=location]") == "dock1", 60, "the robot to dock"
    )
    # The plot shows the drop: a normal charge, then a very low one.
    charges = chart_values(page, 1)
    assert max(charges) >= 50 and min(charges) < 15, charges
    assert 1 in chart_values(page, 2)  # the low speed, on the speed axis
    spans = task_spans(page)
    assert spans.index("AttendingPatient") < spans.index("GoingToDock"), spans
    screen = f"{ROBOT} .lane.mode .span.stand-by"
    wait_for(lambda: page.js(f"document.querySelectorAll('{screen}').length >= 3"), 30)
    marks = page.js(f"document.querySelectorAll('{ROBOT} .timeline .mark').length")
    assert marks >= 1

    # A firing's why, one click away: the rule, its comment, down to who wrote the battery.
    # The list is redrawn as firings come (the newest first): one that comes between finding
    # the button and the mouse's click moves it from under the mouse, and a user clicks again.
    def why_opened() -> bool:
        sentences = page.js(
            f"[...document.querySelectorAll('{ROBOT} .firings .sentence')].map(s => s.textContent)"
        )
        n = next(i for i, s in enumerate(sentences) if s.startswith("battery very low →")) + 1
        page.click(f"{ROBOT} .firings li:nth-child({n}) .why-link")
        time.sleep(0.5)
        return page.js("document.getElementById('why-dialog').open")

    wait_for(why_opened, 10, "the why dialog")
    wait_for(lambda: "by production rule" in (page.text("#why-body") or ""), 20, "the answer")
    answer = page.text("#why-body")
    assert "written by hmi" in answer, answer

    out = REPO / "bench" / "out"
    page.screenshot(out / "hmi-why-1024.png", 1024)
    page.click("#why-close")
    # Then the timeline shows the docking, after the way to the dock (and so do the shots).
    wait_for(lambda: "Docking" in task_spans(page), 60, "the docking on the timeline")
    spans = task_spans(page)
    assert spans.index("GoingToDock") < spans.index("Docking"), spans
    for width in (1024, 1920):
        page.screenshot(out / f"hmi-{width}.png", width)
        overflow = page.js("document.documentElement.scrollWidth - window.innerWidth")
        assert overflow <= 0, f"{overflow} px too wide at {width} px"

    # The history is the space's, not the page's: a reload shows it again.
    page.navigate(f"http://127.0.0.1:{deployment.hmi_port}/")
    wait_for(lambda: "GoingToDock" in task_spans(page), 30, "the history after a reload")
    wait_for(lambda: min(chart_values(page, 1) or [100]) < 15, 10, "the plotted drop")


def post(url: str, body: dict, headers: dict[str, str]) -> int:
    request = urllib.request.Request(
        url, data=json.dumps(body).encode(), headers=headers, method="POST"
    )
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status
    except urllib.error.HTTPError as exc:
        return exc.code


def test_a_cross_origin_post_is_refused_and_changes_nothing(page, deployment):
    base = f"http://127.0.0.1:{deployment.hmi_port}"
    wait_for(lambda: page.text("#status") == "live", 30, "the page to go live")
    wait_for(lambda: page.text(f"{ROBOT} [data-field=task_type]") == "Idle", 30, "the robot")
    # Another origin's page (here: the same server by another name) makes the browser POST,
    # as any web page can; the request is refused.
    page.navigate(f"http://localhost:{deployment.hmi_port}/")
    result = page.call(
        "Runtime.evaluate",
        expression=f"""fetch("{base}/api/battery", {{method: "POST", mode: "no-cors",
             credentials: "include", body: JSON.stringify({{robot: "robot1", level: "empty"}})}})
             .then(() => "answered", e => String(e))""",
        awaitPromise=True,
        returnByValue=True,
    )
    assert result["result"]["value"] == "answered", result  # the server had it, and refused it
    # Without the token, from a foreign Origin, or by a foreign host name: 403.
    with urllib.request.urlopen(f"{base}/", timeout=10) as reply:
        cookie = reply.headers["Set-Cookie"].split(";")[0]
        token = reply.read().decode().split('name="hmi-token" content="')[1].split('"')[0]
    body = {"robot": "robot1", "level": "very low"}
    good = {"Origin": base, "Cookie": cookie, "X-HMI-Token": token}
    assert post(f"{base}/api/battery", body, {**good, "Origin": "http://evil.example"}) == 403
    no_origin = {k: v for k, v in good.items() if k != "Origin"}
    assert post(f"{base}/api/battery", body, no_origin) == 403
    assert post(f"{base}/api/battery", body, {**good, "X-HMI-Token": "0" * 32}) == 403
    assert post(f"{base}/api/battery", body, {**good, "Host": "evil.example"}) == 403
    with TripleSpace.open(f"tcp/127.0.0.1:{deployment.port}", space="ward") as ts:
        assert value(ts, AC.robot1_battery, AC.battery_level) == Literal("normal")
    # The HMI serves this machine only (127.0.0.1), unless `--hmi-listen` says otherwise.
    with pytest.raises(ConnectionRefusedError):
        socket.create_connection(("127.0.0.2", deployment.hmi_port), timeout=5).close()
    # The page's own request, with its session's token and Origin, goes through.
    assert post(f"{base}/api/battery", body, good) == 200
    # The HMI wrote it (the battery monitor may already have answered: never very low on the
    # charger, where the robot stands; so the store's log says it, not the level now).
    with TripleSpace.open(f"tcp/127.0.0.1:{deployment.port}", space="ward") as ts:
        changes, _ = ts.history()
    level = (AC.robot1_battery, AC.battery_level, Literal("very low"))
    assert [c.agent for c in changes if level in c.added] == ["hmi.robot1"], changes[-5:]
