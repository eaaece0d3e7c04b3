import random

import pytest

from agents.sim.devices import SWITCH_DELAY, Driver, drain, obstacles_seen


def test_driver_switches_mode_after_a_delay():
    driver = Driver()
    driver.command("stand-by", now=0)
    driver.step(now=SWITCH_DELAY / 2, dt=SWITCH_DELAY / 2)
    assert driver.mode == "active"
    driver.step(now=SWITCH_DELAY, dt=SWITCH_DELAY / 2)
    assert driver.mode == "stand-by"


def test_commanding_the_current_mode_cancels_a_pending_switch():
    driver = Driver()
    driver.command("disabled", now=0)
    driver.command("active", now=0.1)
    driver.step(now=10, dt=10)
    assert driver.mode == "active"


def test_unknown_mode_or_fault_is_rejected():
    with pytest.raises(ValueError):
        Driver().command("asleep", now=0)
    with pytest.raises(ValueError):
        Driver().inject("broken")


def test_injected_fault_is_reported_until_cleared():
    driver = Driver()
    driver.inject("error")
    driver.step(now=1, dt=1)
    assert driver.fault == "error"
    driver.inject("none")
    assert driver.fault == "none"


def test_random_faults_happen_at_the_given_rate():
    driver = Driver(fault_rate=3600.0, rng=random.Random(1))
    for second in range(1, 20):
        driver.step(now=second, dt=1)
    assert driver.fault == "error"
    assert Driver(fault_rate=0.0).fault == "none"


def test_stand_by_and_disabled_devices_draw_less():
    active = drain([Driver("active"), Driver("active")])
    saving = drain([Driver("stand-by"), Driver("disabled")])
    assert active > saving > 0


def test_laser_sees_crowds_only_when_active():
    assert obstacles_seen("crowded", "active") == "surrounded"
    assert obstacles_seen("empty", "active") == "clear"
    assert obstacles_seen("crowded", "stand-by") is None
