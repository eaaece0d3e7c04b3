"""The HMI shows a reading's life: greyed out when about to expire, then since when it is stale.

The state the page gets (`/api/state`), then the page itself in a headless Chromium.
"""

from __future__ import annotations

import json
import signal
import time
import urllib.request

from agentprocs import HOSPITAL, value
from rdflib import Namespace

from conftest import AC_NS, free_port, wait_for

AC = Namespace(AC_NS)
LIFE = 6.0  # the monitor's lifespan: it renews every 2 s; greyed out in its last 2 s
BATTERY = 'dd[data-field="battery"]'


def _hmi_battery(port: int) -> dict | None:
    """Return the freshness the HMI gives robot1's battery reading (None: none, or no page)."""
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=5) as reply:
            robots = json.load(reply)["robots"]
    except OSError:
        return None
    return next((r.get("battery_fresh") for r in robots if r["name"] == "robot1"), None)


def test_the_hmi_greys_out_a_reading_about_to_expire_then_says_since_when_stale(
    ts, launch, tmp_path
) -> None:
    from test_hmi_browser import CHROMIUM, Browser

    launch.start("reasoner", "--robot-file", str(HOSPITAL))
    wait_for(lambda: value(ts, AC.robot1, AC.current_task) == AC.task_idle, 30, "the robot")
    port = free_port()
    hmi = launch.start("hmi", "--http-port", str(port))
    monitor = launch.start("hw_monitor", "--lifespan", f"{LIFE}s")
    wait_for(lambda: (_hmi_battery(port) or {}).get("expires"), 30, "a leased reading", hmi.logs)
    fresh = _hmi_battery(port)
    assert fresh is not None and 0 < fresh["life"] <= LIFE
    assert time.time() < fresh["expires"] / 1000 <= time.time() + LIFE
    last = str(value(ts, AC.robot1_battery, AC.battery_level))

    browser = Browser(tmp_path / "chromium", f"http://127.0.0.1:{port}/") if CHROMIUM else None
    try:
        if browser is not None:
            classes = f"document.querySelector({json.dumps(BATTERY)})?.className ?? ''"
            wait_for(lambda: browser.text(BATTERY) not in (None, "", "–"), 30, "the battery shown")
            assert "expiring" not in browser.js(classes)  # renewed: not greyed out

        monitor.stop(signal.SIGKILL)
        killed = time.time()
        if browser is not None:
            wait_for(lambda: "expiring" in browser.js(classes), LIFE, "the reading greyed out")
            assert time.time() - killed > LIFE / 6  # not at once: once it missed renewals
        wait_for(lambda: (_hmi_battery(port) or {}).get("stale_since"), LIFE + 3, "stale")
        stale = _hmi_battery(port)
        assert stale is not None and stale["last"] == last
        assert killed < stale["stale_since"] / 1000 <= killed + LIFE + 3
        if browser is not None:
            wait_for(lambda: "stale" in browser.js(classes), 10, "the page saying it is stale")
            shown = browser.text(BATTERY) or ""
            assert shown.startswith("no reading since ") and f"(last: {last})" in shown, shown

        monitor.start()
        wait_for(lambda: (_hmi_battery(port) or {}).get("expires"), 30, "a fresh reading")
        if browser is not None:
            wait_for(lambda: "stale" not in browser.js(classes), 10, "the page fresh again")
    finally:
        if browser is not None:
            browser.close()
