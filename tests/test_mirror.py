"""The one local copy of a space: functional replacement, asserted and inferred kept apart."""

from rdflib import OWL, RDF, Literal, Namespace

from space import Changeset, SpaceMirror
from space.functional import replace_functional

EX = Namespace("http://example.org/")
FUNCTIONAL = (EX.level, RDF.type, OWL.FunctionalProperty)


def test_replace_functional_keeps_the_last_value_and_names_what_it_replaces():
    held = {(EX.b, EX.level): [Literal("normal")]}
    change = replace_functional(
        [
            (EX.b, EX.level, Literal("low")),
            (EX.b, EX.other, EX.x),
            (EX.b, EX.level, Literal("empty")),
        ],
        {EX.level}.__contains__,
        lambda s, p: held.get((s, p), []),
    )
    assert change.kept == [(EX.b, EX.other, EX.x), (EX.b, EX.level, Literal("empty"))]
    assert change.replaced == [(EX.b, EX.level, Literal("normal"))]


def test_a_triple_both_asserted_and_inferred_stays_until_both_are_gone():
    t = (EX.r, RDF.type, EX.Robot)
    mirror = SpaceMirror()
    mirror.apply(Changeset(added=[t], inferred_added=[t]))
    mirror.apply(Changeset(removed=[t]))
    assert t in mirror.graph
    mirror.apply(Changeset(inferred_removed=[t]))
    assert t not in mirror.graph
    assert len(mirror) == 0


def test_snapshot_triples_leave_with_the_first_removal_from_either_graph():
    t = (EX.r, EX.task, EX.dock)
    mirror = SpaceMirror()
    mirror.apply(Changeset(added=[t]), snapshot=True)
    mirror.apply(Changeset(inferred_removed=[t]))
    assert t not in mirror.copy()


def test_a_functional_value_arriving_first_replaces_the_old_one():
    mirror = SpaceMirror([FUNCTIONAL, (EX.b, EX.level, Literal("normal"))])
    mirror.apply(Changeset(inferred_added=[(EX.b, EX.level, Literal("low"))]))
    assert mirror.objects(EX.b, EX.level) == [Literal("low")]
    assert mirror.is_functional(EX.level)
    mirror.remove([FUNCTIONAL])
    assert not mirror.is_functional(EX.level)


def test_what_was_read_says_which_changes_could_change_the_decision():
    mirror = SpaceMirror([(EX.b, EX.level, Literal("normal")), (EX.p, EX.x, Literal(1))])
    with mirror.reading() as reads:
        mirror.value(EX.b, EX.level)
        mirror.subjects(EX.x)
    assert reads.touched_by(Changeset(added=[(EX.b, EX.level, Literal("low"))]))
    assert reads.touched_by(Changeset(inferred_removed=[(EX.q, EX.x, Literal(2))]))
    assert not reads.touched_by(Changeset(added=[(EX.b, EX.speed, Literal(3))]))
    assert not reads.touched_by(Changeset(removed=[(EX.c, EX.level, Literal("low"))]))
    mirror.value(EX.b, EX.speed)  # outside the block: not noted
    assert not reads.touched_by(Changeset(added=[(EX.b, EX.speed, Literal(3))]))
    with mirror.reading() as reads:
        len(mirror.graph)  # rdflib's own lookups are not noted: every change may matter
    assert reads.touched_by(Changeset(added=[(EX.c, EX.speed, Literal(3))]))
