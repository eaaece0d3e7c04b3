import pytest

from agents.sim.base import Base, nearest


def test_base_reaches_target_in_distance_over_speed():
    base = Base(0, 0, max_speed=0.5)
    base.go_to(3, 4)
    steps = 0
    while base.status == "navigating":
        base.step(0.1)
        steps += 1
    assert base.status == "reached"
    assert (base.x, base.y) == (3, 4)
    assert steps == pytest.approx(100, abs=2)


def test_lower_speed_limit_makes_the_trip_longer():
    fast, slow = Base(max_speed=1.0), Base(max_speed=0.3)
    for base in (fast, slow):
        base.go_to(10, 0)
        base.step(5)
    assert fast.x > slow.x
    assert fast.speed == 1.0 and slow.speed == 0.3


def test_disabled_base_aborts_and_stays_put():
    base = Base()
    base.go_to(10, 0)
    base.step(1)
    x = base.x
    base.enabled = False
    base.step(1)
    assert base.status == "aborted"
    assert base.x == x
    assert base.speed == 0.0


def test_nearest_place():
    places = {"dock": (0.0, 0.0), "hall": (6.0, 0.0)}
    assert nearest(places, 1, 1) == "dock"
    assert nearest(places, 4, 0) == "hall"
    assert nearest({}, 0, 0) is None


def test_stopping_without_a_target_is_not_an_abort():
    base = Base()
    base.go_to(10, 0)
    base.step(1)
    base.stop()
    assert base.status == "idle"
    assert base.speed == 0.0
