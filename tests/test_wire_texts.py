"""A changeset read with its terms left as N-Triples texts (`texts=True`, the reasoner's
way) is the same changeset on the wire, and a malformed shape is still refused."""

from __future__ import annotations

import pytest
from rdflib import BNode, Literal, Namespace

from space import Changeset, MalformedPayload

EX = Namespace("http://example.org/")


def test_a_changeset_in_texts_goes_back_on_the_wire_unchanged() -> None:
    cs = Changeset(
        agent="a",
        timestamp="7/abc",
        cause="c",
        added=[(EX.s, EX.p, Literal('two\nlines "quoted"', lang="en")), (BNode("b1"), EX.p, EX.o)],
        removed=[(EX.s, EX.p, Literal(3))],
        inferred_added=[(EX.s, EX.q, Literal("x", datatype=EX.dt))],
        seq=4,
    )
    texts = Changeset.decode(cs.encode(), published=True, texts=True)
    assert texts.texts and texts.added[1] == (
        "_:b1",
        "<http://example.org/p>",
        "<http://example.org/o>",
    )
    assert texts.encode() == cs.encode()
    assert Changeset.decode(texts.encode()) == Changeset.decode(cs.encode())


@pytest.mark.parametrize(
    "triple",
    [
        ["<http://s>", "<http://p>"],
        ['"a literal"', "<http://p>", "<http://o>"],
        ["<http://s>", '"p"', "<http://o>"],
        ["<http://s>", "_:p", "<http://o>"],
        ["<http://s>", "<http://p>", "no term"],
        ["<http://s>", "<http://p>", ""],
        ["<http://s>", "<http://p>", 7],
        "<http://s> <http://p> <http://o>",
    ],
)
def test_a_malformed_shape_is_refused_in_texts_too(triple: object) -> None:
    with pytest.raises(MalformedPayload):
        Changeset.from_wire({"v": 1, "id": "x", "add": [triple]}, texts=True)
