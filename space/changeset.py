"""Changesets: the unit of change of a space, and their msgpack payloads."""

from __future__ import annotations

import uuid
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime

import msgpack

from space.errors import MalformedPayload
from space.terms import Triple, triple_from_nt, triple_to_nt

WIRE_VERSION = 1
LISTS = ("add", "del", "iadd", "idel")  # the wire names of the four triple lists


@dataclass
class Changeset:
    """Triples removed and added atomically, with who, when and why.

    `removed` is applied before `added`. `inferred_*` belong to the space's
    inferred graph (entailments a reasoner maintains); the rest is asserted.
    `seq` is given by the store when it makes the changeset durable.
    """

    id: str = field(default_factory=lambda: uuid.uuid4().hex)
    agent: str = ""
    timestamp: str = ""
    cause: str | None = None
    added: list[Triple] = field(default_factory=list)
    removed: list[Triple] = field(default_factory=list)
    inferred_added: list[Triple] = field(default_factory=list)
    inferred_removed: list[Triple] = field(default_factory=list)
    prefixes: dict[str, str] = field(default_factory=dict)
    seq: int = 0

    def is_empty(self) -> bool:
        """Return True when the changeset changes nothing."""
        return not (self.added or self.removed or self.inferred_added or self.inferred_removed)

    @property
    def time(self) -> datetime | None:
        """Return the wall-clock part of the HLC timestamp, if any."""
        return hlc_datetime(self.timestamp) if self.timestamp else None

    def to_wire(self, texts: Sequence[Sequence[Sequence[str]]] | None = None) -> dict:
        """Return the msgpack-ready map described in docs/wire-format.md.

        `texts`: the N-Triples texts of added, removed, inferred_added and
        inferred_removed, when the caller has them already.
        """
        wire: dict = {"v": WIRE_VERSION, "id": self.id, "agent": self.agent, "ts": self.timestamp}
        if self.cause:
            wire["cause"] = self.cause
        if self.seq:
            wire["seq"] = self.seq
        if self.prefixes:
            wire["prefixes"] = self.prefixes
        if texts is None:
            texts = [[triple_to_nt(t) for t in triples] for triples in self._lists()]
        for name, listed in zip(LISTS, texts, strict=True):
            if listed:
                wire[name] = listed
        return wire

    def _lists(self) -> tuple[list[Triple], ...]:
        return (self.added, self.removed, self.inferred_added, self.inferred_removed)

    def encode(self, texts: Sequence[Sequence[Sequence[str]]] | None = None) -> bytes:
        """Return the msgpack payload (`texts` as in `to_wire`)."""
        return msgpack.packb(self.to_wire(texts), use_bin_type=True)

    @classmethod
    def from_wire(cls, wire: object) -> Changeset:
        """Build a changeset from its decoded map.

        Raises:
            MalformedPayload: a field is missing, of the wrong type, or a term is invalid.
        """
        if not isinstance(wire, dict):
            raise MalformedPayload("a changeset payload is a msgpack map")
        try:
            lists = [[triple_from_nt(t) for t in wire.get(name) or ()] for name in LISTS]
            prefixes = wire.get("prefixes") or {}
            if not isinstance(prefixes, dict):
                raise MalformedPayload("'prefixes' must be a map")
            cs = cls(
                id=str(wire.get("id") or uuid.uuid4().hex),
                agent=str(wire.get("agent") or ""),
                timestamp=str(wire.get("ts") or ""),
                cause=str(wire["cause"]) if wire.get("cause") else None,
                added=lists[0],
                removed=lists[1],
                inferred_added=lists[2],
                inferred_removed=lists[3],
                prefixes={str(k): str(v) for k, v in prefixes.items()},
                seq=int(wire.get("seq") or 0),
            )
        except (TypeError, ValueError) as exc:
            raise MalformedPayload(f"bad changeset field: {exc}") from exc
        if cs.timestamp:
            hlc_key(cs.timestamp)
        return cs

    @classmethod
    def decode(cls, payload: bytes) -> Changeset:
        """Parse a msgpack payload.

        Raises:
            MalformedPayload: not msgpack, or not a changeset.
        """
        return cls.from_wire(unpack(payload))


def unpack(payload: bytes) -> object:
    """Decode msgpack, turning every decoding failure into `MalformedPayload`."""
    try:
        return msgpack.unpackb(payload, raw=False, strict_map_key=False)
    except (ValueError, msgpack.exceptions.ExtraData, msgpack.exceptions.UnpackException) as exc:
        raise MalformedPayload(f"not a msgpack payload: {exc}") from exc


def pack(value: object) -> bytes:
    """Encode a value as msgpack."""
    return msgpack.packb(value, use_bin_type=True)


def hlc_key(timestamp: str) -> tuple[int, str]:
    """Return a sortable key of a Zenoh HLC timestamp string `<ntp64>/<id>`.

    Raises:
        MalformedPayload: the text is not a Zenoh timestamp.
    """
    time_part, sep, ident = timestamp.partition("/")
    if not sep or not time_part.isdigit():
        raise MalformedPayload(f"not a Zenoh HLC timestamp: {timestamp!r}")
    return int(time_part), ident


def hlc_datetime(timestamp: str) -> datetime:
    """Return the wall-clock time of a Zenoh HLC timestamp string."""
    ntp64 = hlc_key(timestamp)[0]
    seconds = ntp64 >> 32
    fraction = (ntp64 & 0xFFFFFFFF) / 2**32
    return datetime.fromtimestamp(seconds + fraction, UTC)
