"""Explanations: why a triple holds, as a tree down to what agents wrote.

A reasoner builds them from its engine's derivations (`space.reasoning.explain`)
and sends them on the space's `@/why` queryable; `TripleSpace.why` reads them
back. The msgpack shape is in docs/wire-format.md.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from datetime import datetime

from space.changeset import hlc_datetime
from space.errors import MalformedPayload
from space.terms import Triple, triple_from_nt, triple_to_nt

ASSERTED = "asserted"
INFERRED = "inferred"
GONE = "gone"  # a premise that held when the rule fired and holds no more (a dropped value)


@dataclass(frozen=True)
class Written:
    """Who wrote an asserted triple, and when: the changeset that last added it."""

    agent: str
    timestamp: str = ""
    changeset: str = ""
    seq: int = 0

    @property
    def time(self) -> datetime | None:
        """Return the wall-clock time of the HLC timestamp, None if unknown."""
        return hlc_datetime(self.timestamp) if self.timestamp else None


@dataclass(frozen=True)
class Explanation:
    """Why one triple holds.

    Attributes:
        triple: the triple explained.
        holds: "asserted" (written by an agent, or by a production rule),
            "inferred" (entailed while its premises hold) or, for a premise only,
            "gone" (it held when the rule fired and holds no more: a value the
            rule replaced, say).
        rule: the rule that concluded it, None for a triple an agent wrote.
        comment: the comment written above that rule in its file, if any.
        where: `file:line` of the rule, if it came from a file.
        premises: the explanations of the facts the rule matched, in body order.
        written: who wrote it (asserted triples; None if the log no longer says).
        repeated: True when this triple is explained higher up in the same tree
            (its premises are then not repeated).
    """

    triple: Triple
    holds: str
    rule: str | None = None
    comment: str | None = None
    where: str | None = None
    premises: tuple[Explanation, ...] = field(default=())
    written: Written | None = None
    repeated: bool = False

    def walk(self, depth: int = 0) -> Iterator[tuple[int, Explanation]]:
        """Yield `(depth, node)` for this node and its premises, depth first."""
        yield depth, self
        for premise in self.premises:
            yield from premise.walk(depth + 1)

    def to_json(self, text: Callable[[Triple], str]) -> dict:
        """Return JSON-ready data: the triple as N-Triples and as `text` says it."""
        out: dict = {"triple": triple_to_nt(self.triple), "text": text(self.triple)}
        out["holds"] = self.holds
        if self.rule is not None:
            out.update(rule=self.rule, comment=self.comment, where=self.where)
        if self.written is not None:
            when = self.written.time
            out["written"] = {
                "agent": self.written.agent,
                "time": when.isoformat() if when else None,
                "changeset": self.written.changeset,
                "seq": self.written.seq or None,
            }
        if self.repeated:
            out["repeated"] = True
        out["premises"] = [p.to_json(text) for p in self.premises]
        return out

    def to_wire(self) -> dict:
        """Return the msgpack-ready map of docs/wire-format.md."""
        wire: dict = {"t": triple_to_nt(self.triple), "holds": self.holds}
        for key, value in (("rule", self.rule), ("comment", self.comment), ("where", self.where)):
            if value:
                wire[key] = value
        if self.written is not None:
            w = self.written
            wire["by"] = {"agent": w.agent, "ts": w.timestamp, "id": w.changeset, "seq": w.seq}
        if self.premises:
            wire["from"] = [p.to_wire() for p in self.premises]
        if self.repeated:
            wire["seen"] = True
        return wire

    @classmethod
    def from_wire(cls, wire: object) -> Explanation:
        """Build an explanation from its decoded map.

        Raises:
            MalformedPayload: a field is missing or of the wrong type.
        """
        if not isinstance(wire, dict):
            raise MalformedPayload(f"an explanation is a map, got {type(wire).__name__}")
        holds = wire.get("holds")
        if holds not in (ASSERTED, INFERRED, GONE):
            raise MalformedPayload(
                f"an explanation holds 'asserted', 'inferred' or 'gone', got {holds!r}"
            )
        by = wire.get("by")
        premises = wire.get("from") or []
        if not isinstance(premises, list) or (by is not None and not isinstance(by, dict)):
            raise MalformedPayload("an explanation's 'from' is a list and its 'by' a map")
        try:
            written = None
            if by is not None:
                written = Written(
                    agent=str(by.get("agent") or ""),
                    timestamp=str(by.get("ts") or ""),
                    changeset=str(by.get("id") or ""),
                    seq=int(by.get("seq") or 0),
                )
            return cls(
                triple=triple_from_nt(wire.get("t")),
                holds=holds,
                rule=_text(wire.get("rule")),
                comment=_text(wire.get("comment")),
                where=_text(wire.get("where")),
                premises=tuple(cls.from_wire(p) for p in premises),
                written=written,
                repeated=bool(wire.get("seen")),
            )
        except (TypeError, ValueError) as exc:
            raise MalformedPayload(f"bad explanation field: {exc}") from exc


def _text(value: object) -> str | None:
    return None if value is None else str(value)
