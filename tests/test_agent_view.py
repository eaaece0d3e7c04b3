"""An agent's view of the space: functional values replaced, firing records left out."""

from rdflib import OWL, RDF, Literal, Namespace

from agents.firings import FiringLog
from agents.view import View
from conftest import AC_NS

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


def test_firing_records_stay_out_of_the_view():
    added, _dropped = FiringLog().record("some_rule", "cause-1", AC.robot1)
    view = View(added)
    assert len(view.graph) == 0
