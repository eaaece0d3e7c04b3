"""An agent's view of the space: functional values replaced, only what concerns its robot."""

from rdflib import OWL, RDF, Literal, Namespace

from agents.firings import FiringLog
from agents.view import View
from conftest import AC_NS
from space import triple_from_nt

AC = Namespace(AC_NS)
FUNCTIONAL = (AC.battery_level, RDF.type, OWL.FunctionalProperty)


def test_a_functional_value_replaces_the_old_one_even_before_its_removal_arrives():
    view = View([FUNCTIONAL, (AC.b, AC.battery_level, Literal("normal"))])
    view.add([(AC.b, AC.battery_level, Literal("low")), (AC.r, AC.has_device, AC.b)])
    view.add([(AC.r, AC.has_device, AC.c)])
    assert view.objects(AC.b, AC.battery_level) == [Literal("low")]
    assert view.objects(AC.r, AC.has_device) == [AC.b, AC.c]
    view.remove([FUNCTIONAL])
    view.add([(AC.b, AC.battery_level, Literal("normal"))])
    assert len(view.objects(AC.b, AC.battery_level)) == 2


def test_a_robots_agent_keeps_neither_records_nor_other_robots_of_a_snapshot():
    texts, _dropped = FiringLog().record(["some_rule"], "cause-1", AC.robot1)
    record = [triple_from_nt(t) for t in texts]
    mine = [(AC.robot1, RDF.type, AC.Robot), (AC.robot1_battery, AC.charge_percent, Literal(5))]
    site = [
        (AC.hall, AC.crowd_level, Literal("high")),
        (AC.battery_low, AC.below_percent, Literal(20)),
    ]
    others = [(AC.robot12, RDF.type, AC.Robot), (AC.robot12_battery, AC.charge_percent, Literal(9))]
    view = View(View.concerning([*record, *mine, *site, *others], AC.robot1))
    assert set(view.graph) == {*mine, *site}  # robot12 starts with "robot1": another robot still


def test_a_robots_devices_not_named_after_it_are_told():
    view = View(
        [
            (AC.robot1, AC.has_device, AC.robot1_battery),
            (AC.robot1, AC.has_device, AC.spare_laser),
            (AC.robot1, AC.has_skill, AC.robot1_navigation),
        ]
    )
    assert view.strays(AC.robot1) == [AC.spare_laser]
