"""Changesets: the unit of change of a space, and their msgpack payloads."""

from __future__ import annotations

import uuid
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime

import msgpack

from space.errors import MalformedPayload
from space.terms import Triple, text_triple, triple_from_nt, triple_to_nt

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
    lifespan: float | None = None  # seconds the added triples live unless written again
    texts: bool = False  # the triples are N-Triples texts `(s, p, o)`, as on the wire

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
        if self.lifespan is not None:
            wire["lifespan"] = self.lifespan
        if self.prefixes:
            wire["prefixes"] = self.prefixes
        if texts is None:
            texts = (
                self._lists()
                if self.texts
                else [[triple_to_nt(t) for t in triples] for triples in self._lists()]
            )
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
    def from_wire(cls, wire: object, *, published: bool = False, texts: bool = False) -> Changeset:
        """Build a changeset from its decoded map.

        A writer's changeset must carry its `id`; one the store published or
        logged (`published=True`) also its `seq` (see `published_seq`). With
        `texts`, its triples stay N-Triples texts, checked for shape only
        (`space.terms.text_triple`): the reader parses each term where it meets it.

        Raises:
            MalformedPayload: a field is missing, of the wrong type, or a term is invalid.
        """
        seq = published_seq(wire) if published else None
        wire = _checked(wire)
        triple = text_triple if texts else triple_from_nt
        try:
            lists = [[triple(t) for t in wire.get(name) or ()] for name in LISTS]
            prefixes = wire.get("prefixes") or {}
            if not isinstance(prefixes, dict):
                raise MalformedPayload("'prefixes' must be a map")
            cs = cls(
                id=wire["id"],
                agent=str(wire.get("agent") or ""),
                timestamp=str(wire.get("ts") or ""),
                cause=str(wire["cause"]) if wire.get("cause") else None,
                added=lists[0],
                removed=lists[1],
                inferred_added=lists[2],
                inferred_removed=lists[3],
                prefixes={str(k): str(v) for k, v in prefixes.items()},
                seq=seq if seq is not None else int(wire.get("seq") or 0),
                lifespan=float(wire["lifespan"]) if wire.get("lifespan") else None,
                texts=texts,
            )
        except (TypeError, ValueError) as exc:
            raise MalformedPayload(f"bad changeset field: {exc}") from exc
        if cs.timestamp:
            hlc_key(cs.timestamp)
        return cs

    @classmethod
    def decode(cls, payload: bytes, *, published: bool = False, texts: bool = False) -> Changeset:
        """Parse a msgpack payload (`published` and `texts` as in `from_wire`).

        Raises:
            MalformedPayload: not msgpack, or not a changeset.
        """
        return cls.from_wire(unpack(payload), published=published, texts=texts)


def _checked(wire: object) -> dict:
    """Return a changeset map after checking what every one carries: a string id, a known version.

    Raises:
        MalformedPayload: naming the field that is missing or wrong.
    """
    if not isinstance(wire, dict):
        raise MalformedPayload("a changeset payload is a msgpack map")
    ident = wire.get("id")
    if not isinstance(ident, str) or not ident:
        raise MalformedPayload(f"a changeset has a non-empty string 'id', got {ident!r}")
    version = wire.get("v", WIRE_VERSION)
    if version != WIRE_VERSION:
        raise MalformedPayload(f"unknown changeset version {version!r} (this is {WIRE_VERSION})")
    return wire


def published_seq(wire: object) -> int:
    """Return the sequence number of a changeset the store published or logged.

    Checked before anything else is read, so that a subscriber that skips a
    changeset unparsed still refuses a malformed one, and trusts no seq of a
    message that is not a changeset.

    Raises:
        MalformedPayload: not a changeset map with an id, or no positive integer `seq`.
    """
    seq = _checked(wire).get("seq")
    if not isinstance(seq, int) or isinstance(seq, bool) or seq < 1:
        raise MalformedPayload(f"a published changeset has a positive integer 'seq', got {seq!r}")
    return seq


def unpack(payload: bytes) -> object:
    """Decode msgpack, turning every decoding failure into `MalformedPayload`.

    A map keyed by a list or a map is valid msgpack Python cannot hold: msgpack
    raises TypeError (unhashable), which would otherwise end a subscriber's
    dispatcher thread on one forged message.
    """
    try:
        return msgpack.unpackb(payload, raw=False, strict_map_key=False)
    except (
        ValueError,
        TypeError,
        msgpack.exceptions.ExtraData,
        msgpack.exceptions.UnpackException,
    ) as exc:
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
