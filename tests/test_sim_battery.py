from agents.sim.battery import DEFAULT_LEVELS, Battery, level_of, middle_of


def test_levels_follow_the_integrators_thresholds():
    assert level_of(5) == "very low"
    assert level_of(10) == "low"
    assert level_of(24.9) == "low"
    assert level_of(50) == "normal"
    assert level_of(100) == "full"
    assert level_of(30, {"empty": 20, "some": 60, "plenty": 101}) == "some"


def test_battery_drains_faster_with_more_load_and_when_moving():
    idle, busy, moving = Battery(50), Battery(50), Battery(50)
    idle.step(100)
    busy.step(100, device_drain=0.01)
    moving.step(100, device_drain=0.01, moving=True)
    assert 50 > idle.percent > busy.percent > moving.percent


def test_battery_charges_on_the_dock_up_to_full():
    battery = Battery(9, charging=True)
    battery.step(100)
    assert battery.percent > 9
    battery.step(10_000)
    assert battery.percent == 100
    assert level_of(battery.percent, DEFAULT_LEVELS) == "full"


def test_battery_never_goes_below_empty():
    battery = Battery(1)
    battery.step(10_000, device_drain=1)
    assert battery.percent == 0


def test_reported_charge_moves_in_coarse_steps():
    assert Battery(83.7).reported_percent() == 80
    assert Battery(9.9).reported_percent() == 5


def test_a_charging_battery_is_never_very_low():
    # "very low" sends the robot to its dock; on the charger that call is answered.
    assert level_of(3, charging=True) == "low"
    assert level_of(50, charging=True) == "normal"
    assert level_of(3, {"only": 101}, charging=True) == "only"


def test_a_level_set_without_a_charge_gets_one_in_its_middle():
    assert middle_of("very low") == 5
    assert middle_of("low") == 17
    assert level_of(middle_of("normal")) == "normal"


def test_an_adopted_charge_is_published_back_unchanged_until_it_drains_a_step():
    for published in (5, 17, 40):
        battery = Battery()
        battery.adopt(published)
        battery.step(1)
        assert battery.reported_percent() == published // 5 * 5
        assert level_of(battery.percent) == level_of(published)
