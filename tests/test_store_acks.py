"""An acknowledgement tells the truth: the triples the store did not apply, and why."""

import uuid
from pathlib import Path

import msgpack
import pytest
from rdflib import Literal, Namespace
from rdflib.namespace import OWL, RDF

from conftest import AC_NS
from space import NotApplied

AC = Namespace(AC_NS)


def _functional(ts) -> None:
    ts.write([(AC.battery_level, RDF.type, OWL.FunctionalProperty)])


def test_a_value_that_lost_to_a_newer_one_is_reported_not_acknowledged_as_done(ts):
    _functional(ts)
    older = ts.changeset([(AC.b1, AC.battery_level, Literal("high"))])
    newer = ts.changeset([(AC.b1, AC.battery_level, Literal("low"))])
    assert ts.send(newer).dropped == []
    ack = ts.send(older)
    assert ack == older.id  # still the id, as before
    assert [d.triple for d in ack.dropped] == [(AC.b1, AC.battery_level, Literal("high"))]
    assert "newer value" in ack.dropped[0].reason
    assert set(ts.query((AC.b1, AC.battery_level, None)).objects()) == {Literal("low")}


def test_strict_mode_raises_naming_the_triple_and_the_rest_is_applied(ts):
    _functional(ts)
    older = ts.changeset(
        [(AC.b2, AC.battery_level, Literal("high")), (AC.b2, AC.checked, Literal(True))]
    )
    ts.send(ts.changeset([(AC.b2, AC.battery_level, Literal("low"))]))
    with pytest.raises(NotApplied, match="battery_level") as caught:
        ts.send(older, strict=True)
    assert len(caught.value.ack.dropped) == 1
    assert (AC.b2, AC.checked, Literal(True)) in set(ts.query((AC.b2, None, None)))


def test_two_values_of_a_functional_property_in_one_changeset_keep_the_last(ts):
    _functional(ts)
    ack = ts.write(
        [(AC.b3, AC.battery_level, Literal("high")), (AC.b3, AC.battery_level, Literal("low"))]
    )
    assert [d.triple[2] for d in ack.dropped] == [Literal("high")]
    assert "same changeset" in ack.dropped[0].reason
    assert set(ts.query((AC.b3, AC.battery_level, None)).objects()) == {Literal("low")}


def test_cli_write_prints_what_was_not_applied_and_strict_exits_1(ts, run_tspace, tmp_path: Path):
    _functional(ts)
    doc = tmp_path / "two.ttl"
    doc.write_text(f'@prefix ac: <{AC_NS}> .\nac:b4 ac:battery_level "high", "low" .\n')
    done = run_tspace("write", str(doc))
    assert done.returncode == 0, done.stderr
    assert "not applied" in done.stderr and "battery_level" in done.stderr
    strict = run_tspace("write", "--strict", str(doc))
    assert strict.returncode == 1
    assert "not applied" in strict.stderr


def test_a_retry_gets_the_first_ack_with_what_was_not_applied(ts):
    _functional(ts)
    older = ts.changeset([(AC.b5, AC.battery_level, Literal("high")), (AC.b5, AC.seen, Literal(1))])
    ts.send(ts.changeset([(AC.b5, AC.battery_level, Literal("low"))]))
    first = ts.send(older)
    again = ts.send(older)  # as a client would after a lost reply
    assert again.again and not first.again
    assert again.seq == first.seq
    assert again.dropped == first.dropped and len(first.dropped) == 1
    assert ts.snapshot()[1] == first.seq, "applied once"


def test_a_functional_value_read_again_after_each_way_it_can_change(ts):
    # The store remembers the values it replaced (space/store/values.py); each of
    # these changes must reach what it remembers, or a value would be kept twice.
    _functional(ts)
    for level in range(30):
        ts.write([(AC.b9, AC.battery_level, Literal(level))])
    assert set(ts.query((AC.b9, AC.battery_level, None)).objects()) == {Literal(29)}
    ts.remove([(AC.b9, AC.battery_level, Literal(29))])
    ts.write([(AC.b9, AC.battery_level, Literal("low"))])
    assert set(ts.query((AC.b9, AC.battery_level, None)).objects()) == {Literal("low")}
    ts.remove([(AC.battery_level, RDF.type, OWL.FunctionalProperty)])
    ts.write([(AC.b9, AC.battery_level, Literal("also"))])  # not functional now: a second value
    _functional(ts)
    ts.write([(AC.b9, AC.battery_level, Literal("last"))])
    assert set(ts.query((AC.b9, AC.battery_level, None)).objects()) == {Literal("last")}


def test_a_triple_removed_after_each_way_it_can_come_back_is_removed(ts):
    # The store remembers the triples its latest commits added or removed
    # (space/store/values.py); each way a triple comes back must reach that memory,
    # or removing it again would be taken for a no-op and the triple kept.
    t = (AC.r7, AC.colour, Literal("red"))
    ts.write([t])  # added as text (a plain write)
    ts.remove([t])
    ts.write([t])  # back as text again, after the store noted it absent
    ts.remove([t])
    assert not ts.query((AC.r7, AC.colour, None))
    ts.apply([t], [(AC.r7, AC.colour, Literal("blue"))])  # back in a term-by-term changeset
    ts.remove([t])
    assert not ts.query((AC.r7, AC.colour, None))


def test_a_request_sent_twice_in_a_burst_is_applied_once_and_acknowledged_alike(ts):
    # The copies land in one batch of the store's (or the next): the second is answered
    # with the first's outcome, marked `again`, and nothing is applied twice.
    key = f"tspace/{ts.space}/@/write"
    ident = uuid.uuid4().hex
    twice = {"v": 1, "id": ident, "add": [[f"<{AC_NS}r8>", f"<{AC_NS}count>", '"1"']]}
    others = [
        {"v": 1, "id": uuid.uuid4().hex, "add": [[f"<{AC_NS}r8>", f"<{AC_NS}n>", f'"{i}"']]}
        for i in range(20)
    ]
    burst = [*others[:10], twice, *others[10:], twice]
    gets = [ts.session.get(key, payload=msgpack.packb(w), timeout=5) for w in burst]
    acks = [msgpack.unpackb(next(iter(g)).ok.payload.to_bytes()) for g in gets]
    first, second = acks[10], acks[-1]
    assert first["id"] == second["id"] == ident and first["seq"] == second["seq"]
    assert not first.get("again") and second.get("again")
    assert len(ts.query((AC.r8, None, None))) == 21
    seqs = [a["seq"] for a in acks[:10] + acks[11:-1]]
    assert first["seq"] not in seqs and len(set(seqs)) == 20


def test_a_triple_a_bulk_changeset_removed_is_written_again(ts):
    # A changeset of more than `values.BULK` triples is not remembered triple by triple:
    # its space's memory is forgotten instead, or a triple it removed would still be
    # taken as held, and writing it again dropped as a no-op.
    t = (AC.r10, AC.colour, Literal("red"))
    ts.apply([t], [(AC.r10, AC.colour, Literal("blue"))])  # term by term: remembered held
    ts.apply([(AC.r10, AC.n, Literal(i)) for i in range(2_001)], [t])  # removed in bulk
    ts.write([t])
    assert ts.query(t)
