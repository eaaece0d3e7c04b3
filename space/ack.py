"""A write's acknowledgement: what the store applied, and what it did not and why."""

from __future__ import annotations

from typing import NamedTuple

from space.errors import MalformedPayload, NotApplied
from space.terms import Triple, triple_from_nt


class Dropped(NamedTuple):
    """An added triple the store did not apply, and why (a newer functional value, say)."""

    triple: Triple
    reason: str


class Ack(str):
    """The id of an acknowledged changeset (a `str`, as before), with what the store said.

    Attributes:
        seq: the space's sequence number after the changeset (before it, if it changed nothing).
        dropped: the added triples not applied, each with its reason; empty when all were.
        again: True when the store had applied this changeset already (a retry).
    """

    seq: int
    dropped: list[Dropped]
    again: bool

    @classmethod
    def of(cls, ident: str, reply: dict) -> Ack:
        """Build the acknowledgement of changeset `ident` from the store's reply map.

        Raises:
            MalformedPayload: the reply's `dropped` is not a list of `{triple, reason}`.
        """
        ack = cls(ident)
        ack.seq = int(reply.get("seq") or 0)
        ack.again = bool(reply.get("again"))
        ack.dropped = []
        for item in reply.get("dropped") or ():
            if not isinstance(item, dict):
                raise MalformedPayload(f"unexpected 'dropped' entry in an ack: {item!r:.80}")
            ack.dropped.append(Dropped(triple_from_nt(item.get("triple")), str(item.get("reason"))))
        return ack

    def check(self) -> Ack:
        """Return self, or raise NotApplied when some triple was not applied (strict mode)."""
        if self.dropped:
            lines = "; ".join(f"{_nt(d.triple)}: {d.reason}" for d in self.dropped)
            raise NotApplied(self, f"{len(self.dropped)} triple(s) not applied: {lines}")
        return self


def _nt(t: Triple) -> str:
    return " ".join(x.n3() for x in t)
