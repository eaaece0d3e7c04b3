"""Decide what a changeset really changes in one space, and give it its seq.

This is the "decide and order" half of the store (see `space/store/__init__.py`):
functional properties replace their old value, the later HLC timestamp wins,
only net changes are logged and published, and each net changeset gets the
next sequence number. It reads the database and, within a batch not yet
committed, its own overlay of the batch's earlier changesets; it never writes:
what it decides is an `Entry` the server commits.
"""

from __future__ import annotations

from dataclasses import dataclass

import pyoxigraph as ox

from space._parts import header
from space.changeset import WIRE_VERSION, hlc_key, pack, published_seq
from space.prefixes import PrefixMap
from space.store import oxterms
from space.store.db import StoreDB
from space.store.db_layout import FUNCTIONAL, Entry
from space.store.intake import LISTS, WriteRequest
from space.store.lifespans import Leases
from space.store.oxterms import OxTerm, OxTriple

_TYPE, _FUNCTIONAL_CLASS = (ox.NamedNode(x) for x in FUNCTIONAL)
_TYPE_TEXT, _FUNCTIONAL_TEXT = (f"<{x}>" for x in FUNCTIONAL)
Row = tuple[str, str, str]


@dataclass
class Net:
    """A decided changeset: its log entry, and what its writer is told was not applied."""

    entry: Entry
    texts: list[list[list[str]]]  # N-Triples of add, del, iadd, idel (for triple keys)
    header: dict  # what each of its parts repeats (`space._parts.header`): parts are cut from texts


class SpaceState:
    """One space's sequence number, prefixes and functional-property timestamps.

    Worker thread only. After a failed commit the server drops it and loads a
    new one from the database (`StoreDB.load`), so it never runs ahead of disk.
    """

    def __init__(self, name: str, db: StoreDB) -> None:
        loaded = db.load(name)
        self.name = name
        self.db = db
        self.seq = loaded.seq
        self.prefixes = PrefixMap(loaded.prefixes)
        self._stamps = loaded.stamps
        self._functional = loaded.functional
        self._functional_texts: set[str] | None = None  # their N-Triples, made when asked
        self._overlay: dict[tuple[str, OxTriple], bool] = {}
        self._pending_objects: dict[tuple[OxTerm, OxTerm], set[OxTerm]] = {}
        self._refresh_functional = False
        self._plain_rows: set[Row] = set()  # the batch's plain additions (see `decide`)
        self._plain_subjects: set[str] = set()
        self.leases: Leases | None = None  # the store's, once it serves this space

    def settle(self) -> None:
        """Forget the overlay once its batch is committed."""
        self._overlay.clear()
        self._pending_objects.clear()
        self._plain_rows.clear()
        self._plain_subjects.clear()
        if self._refresh_functional:
            self._functional = self.db.functional(self.name)
            self._functional_texts = None
            self._refresh_functional = False

    def takes_plain(self, req: WriteRequest) -> bool:
        """Return whether a write can be decided on its texts alone (`req.plain`).

        It can when no functional property is in it (no timestamp to weigh, no
        old value to replace), no lease is in play (it has no lifespan, and no
        triple of this space is leased), and no changeset of the batch was
        decided term by term in this space before it (its overlay is in terms).
        """
        if req.plain is None or self._overlay or req.lifespan:
            return False
        if self.leases is not None and (
            self.leases.holds(self.name) or self.leases.has_garbage(self.name)
        ):
            return False
        predicates = {row[1] for row in req.plain}
        if _TYPE_TEXT in predicates and any(
            row[1] == _TYPE_TEXT and row[2] == _FUNCTIONAL_TEXT for row in req.plain
        ):
            return False
        if self._functional_texts is None:
            self._functional_texts = {oxterms.text(p) for p in self._functional}
        return not predicates & self._functional_texts

    @property
    def pending_plain(self) -> bool:
        """Return whether the batch holds plain changesets of this space (see `takes_plain`)."""
        return bool(self._plain_rows)

    def decide(self, req: WriteRequest, stamp: str) -> tuple[Net | None, list[dict]]:
        """Return the net changeset of a write with the next seq (None if nothing changes).

        Also returns the additions not applied and why (`{"triple", "reason"}`),
        for the writer's acknowledgement. A plain write (`req.plain`) must be one
        this state `takes_plain`; any other must come after its batch's plain ones
        are committed (`pending_plain`).
        """
        if req.plain is not None:
            return self._decide_plain(req, req.plain, stamp), []
        kept, replaced, dropped, known = self._functional_additions(req.added, stamp)
        removed, added = self._net("t", req.removed + replaced, kept, known)
        i_removed, i_added = self._net("i", req.inferred_removed, req.inferred_added)
        if self.leases is not None:
            self.leases.decide(self.name, req.id, req.lifespan, kept, removed)
        new_prefixes = self.prefixes.update(req.prefixes)
        if not (removed or added or i_removed or i_added or new_prefixes):
            return None, dropped
        entry = Entry(
            space=self.name,
            seq=self.seq + 1,
            request=req.id,
            payload=b"",
            removed=removed,
            added=added,
            inferred_removed=i_removed,
            inferred_added=i_added,
            prefixes=new_prefixes,
        )
        self._stamp(entry, stamp)
        texts = [
            [oxterms.triple_text(t) for t in ts] for ts in (added, removed, i_added, i_removed)
        ]
        return self._ordered(req, entry, texts, stamp), dropped

    def _ordered(self, req: WriteRequest, entry: Entry, texts: list, stamp: str) -> Net:
        """Give a decided entry its payload (what is logged and published); count its seq."""
        wire: dict = {"v": WIRE_VERSION, "id": req.id, "agent": req.agent, "ts": stamp}
        if req.cause:
            wire["cause"] = req.cause
        wire["seq"] = entry.seq
        if req.lifespan:
            wire["lifespan"] = req.lifespan
        if entry.prefixes:
            wire["prefixes"] = entry.prefixes
        for name, listed in zip(LISTS, texts, strict=True):
            if listed:
                wire[name] = listed
        entry.payload = pack(wire)
        self.seq = entry.seq
        return Net(entry, texts, header(wire))

    def _decide_plain(self, req: WriteRequest, rows: list, stamp: str) -> Net | None:
        """Decide a write of plain additions on their texts (`oxterms.plain_rows`).

        A text is its triple here, so duplicates are found by text, and a triple
        is looked up in the database only when its subject is there already.
        """
        new = self._new_rows(list(dict.fromkeys(map(tuple, rows))))
        prefixes = self.prefixes.update(req.prefixes)
        if not (new or prefixes):
            return None
        entry = Entry(
            space=self.name,
            seq=self.seq + 1,
            request=req.id,
            payload=b"",
            plain=new,  # type: ignore[arg-type]
            prefixes=prefixes,
        )
        return self._ordered(req, entry, [new, [], [], []], stamp)

    def _new_rows(self, rows: list[Row]) -> list[Row]:
        """Return the rows neither in the database nor added earlier in the batch; note them.

        A subject's rows are looked up one by one only if the subject is known: one
        lookup of the subject spares those of a new one's rows. A subject of one
        row is looked up by that row alone (a sensor's write: one lookup, not two).
        """
        count: dict[str, int] = {}
        for row in rows:
            count[row[0]] = count.get(row[0], 0) + 1
        known = {
            s: n == 1
            or s in self._plain_subjects
            or self.db.has_subject(self.name, oxterms.term(s))
            for s, n in count.items()
        }
        new = [
            row
            for row in rows
            if not known[row[0]]
            or not (row in self._plain_rows or self.db.has(self.name, "t", oxterms.triple(row)))
        ]
        self._plain_rows.update(new)
        self._plain_subjects.update(row[0] for row in new)
        return new

    def install(self, wire: dict, payload: bytes) -> Net:
        """Take a committed net changeset exactly as given (`wire`, `payload` its encoding).

        The overlay is not touched: nothing is decided on it before the batch it
        is applied in is committed and `settle` is called.

        Raises:
            MalformedPayload: not a published changeset.
        """
        seq = published_seq(wire)
        lists = [[oxterms.triple(t) for t in wire.get(name) or ()] for name in LISTS]
        added, removed, i_added, i_removed = lists
        prefixes = self.prefixes.update(wire.get("prefixes") or {})
        entry = Entry(
            space=self.name,
            seq=seq,
            request=str(wire.get("id") or ""),
            payload=payload,
            removed=removed,
            added=added,
            inferred_removed=i_removed,
            inferred_added=i_added,
            prefixes=prefixes,
        )
        self._stamp(entry, str(wire.get("ts") or ""))
        self.seq = seq
        texts = [[oxterms.triple_text(t) for t in ts] for ts in lists]
        return Net(entry, texts, header(wire))

    def _stamp(self, entry: Entry, stamp: str) -> None:
        """Record the timestamps of functional values the entry adds or removes."""
        for t in (*entry.removed, *entry.added, *entry.inferred_removed, *entry.inferred_added):
            if t[1] == _TYPE and t[2] == _FUNCTIONAL_CLASS:
                self._refresh_functional = True
                self._functional.add(t[0])
                self._functional_texts = None
        for s, p, _o in entry.removed:
            old = self._stamps.pop((s, p), None)
            if old is not None:
                entry.stamps_removed.append((s, p, ox.Literal(old)))
        if not stamp:
            return
        for s, p, _o in entry.added:
            if p in self._functional:
                old = self._stamps.get((s, p))
                if old is not None and old != stamp:
                    entry.stamps_removed.append((s, p, ox.Literal(old)))
                self._stamps[(s, p)] = stamp
                entry.stamps_added.append((s, p, ox.Literal(stamp)))

    def _functional_additions(
        self, added: list[OxTriple], stamp: str
    ) -> tuple[list[OxTriple], list[OxTriple], list[dict], dict[OxTriple, bool]]:
        """Split additions into those kept, the old values they replace, and those dropped.

        Also returns whether the asserted graph holds each functional triple kept or
        replaced: the objects of its pair were read whole, so `_net` need not look
        them up (a sensor's new reading is in no recent commit, and the database's
        answer that it is absent cost a RocksDB iterator). Additions come with their
        literals in the database's canonical form (`oxterms.canonical_all`), so they
        compare with the objects read as the database compares them.
        """
        kept: list[OxTriple] = []
        replaced: list[OxTriple] = []
        dropped: list[dict] = []
        known: dict[OxTriple, bool] = {}
        latest: dict[tuple[OxTerm, OxTerm], OxTriple] = {}
        for t in added:
            if t[1] in self._functional:
                earlier = latest.get((t[0], t[1]))
                if earlier is not None and earlier != t:
                    dropped.append(
                        _dropped(
                            earlier,
                            "a later value of this functional property in the same changeset",
                        )
                    )
                latest[(t[0], t[1])] = t
            else:
                kept.append(t)
        for (s, p), t in latest.items():
            held = self._stamps.get((s, p))
            objects = self._objects(s, p)
            if held and stamp and hlc_key(stamp) < hlc_key(held):
                if t[2] not in objects:
                    why = f"a newer value is held (written at {held}, this at {stamp})"
                    dropped.append(_dropped(t, why))
                continue
            kept.append(t)
            known[t] = t[2] in objects
            for o in objects:
                if o != t[2]:
                    replaced.append((s, p, o))
                    known[(s, p, o)] = True
        return kept, replaced, dropped, known

    def _objects(self, s: OxTerm, p: OxTerm) -> list[OxTerm]:
        overlay = self._overlay
        held = self.db.objects(self.name, s, p)
        found = [o for o in held if overlay.get(("t", (s, p, o))) is not False]
        for o in self._pending_objects.get((s, p), ()):
            if o not in found and self._overlay.get(("t", (s, p, o))):
                found.append(o)
        return found

    def holds(self, t: OxTriple) -> bool:
        """Return whether the asserted graph holds a triple, counting the batch's writes so far."""
        return self._has("t", t)

    def _has(self, which: str, t: OxTriple) -> bool:
        held = self._overlay.get((which, t))
        return held if held is not None else self.db.has(self.name, which, t)

    def _net(
        self,
        which: str,
        removed: list[OxTriple],
        added: list[OxTriple],
        known: dict[OxTriple, bool] | None = None,
    ) -> tuple[list[OxTriple], list[OxTriple]]:
        """Return what removing then adding really changes in a graph; note it in the overlay.

        `known`: whether the graph holds some of the triples, already read.
        """
        read = known or {}

        def has(t: OxTriple) -> bool:
            held = read.get(t)
            return self._has(which, t) if held is None else held

        gone = {t: None for t in removed if has(t)}
        new = {t: None for t in added if t in gone or not has(t)}
        net_removed = [t for t in gone if t not in new]
        net_added = [t for t in new if t not in gone]
        self._intend(which, net_removed, net_added)
        return net_removed, net_added

    def _intend(self, which: str, removed: list, added: list) -> None:
        """Note in the overlay that `removed` is absent and `added` present in graph `which`."""
        for t in removed:
            self._overlay[(which, t)] = False
        for t in added:
            self._overlay[(which, t)] = True
            if which == "t":
                self._pending_objects.setdefault((t[0], t[1]), set()).add(t[2])


def _dropped(t: OxTriple, reason: str) -> dict:
    return {"triple": oxterms.triple_text(t), "reason": reason}
