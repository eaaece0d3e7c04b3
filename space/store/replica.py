"""A follower store's side of replication: catch up from the leader, then follow it.

The leader's net changesets (what it publishes on `@/changes` and keeps in its
log) are installed exactly, in sequence order; a gap is filled from the
leader's log; each install is confirmed on `@repl/ack` so the leader can
acknowledge writes that every replica holds.

A log only continues a state it shares: the leader's changeset at this store's
last sequence number must be this store's own. When it is not (this store led
on its own during a network split) or the leader no longer keeps it (this store
was away longer than the leader's log reaches), the space is copied whole from
the leader (`@repl/state`) instead.

Every step says whether it got what it asked the leader for: a store that could
not catch up is behind, and the server keeps it silent until a retry succeeds.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import zenoh

from space import keys
from space._request import ask_store
from space.changeset import Changeset, pack
from space.errors import MalformedPayload, SpaceError
from space.store.db import CommitFailed, StoreDB
from space.store.state import SpaceState

log = logging.getLogger("tspace.store")


class Replica:
    """Keep the spaces of a follower store equal to the leader's. Worker thread only."""

    def __init__(
        self,
        session: zenoh.Session,
        root: str,
        db: StoreDB,
        space: Callable[[str], SpaceState],
        forget: Callable[[str], None],
    ) -> None:
        self.session = session
        self.root = root
        self.db = db
        self.space = space
        self.forget = forget

    def catch_up(self) -> bool:
        """Fetch from the leader what this store missed, space by space (blocks).

        Returns False when the leader did not answer for a space: this store is behind.
        """
        try:
            reply = ask_store(self.session, f"{self.root}/@repl/spaces", b"", 5.0, what="sync")
        except SpaceError as exc:
            log.warning("could not ask the leader for its spaces: %s", exc)
            return False
        for name, seq in reply.items():
            if not self._fetch(self.space(str(name)), int(seq)):
                return False
        return True

    def follow(self, published: list[tuple[str, bytes]]) -> bool:
        """Install changesets the leader published, `(space, payload)`, and confirm them.

        Returns False when a gap before one of them could not be fetched: this
        store is behind (nothing is confirmed then).
        """
        touched: dict[str, int] = {}
        for space, payload in published:
            try:
                net = Changeset.decode(payload)
            except MalformedPayload as exc:
                log.warning("malformed replicated change on %r skipped: %s", space, exc)
                continue
            state = self.space(space)
            if net.seq > state.seq + 1:
                if not self._fetch(state, net.seq - 1):
                    return False
                state = self.space(space)  # a new state if the space was copied whole
            if net.seq == state.seq + 1:
                self._install(state, [payload])
            touched[space] = state.seq
        if touched:
            self.confirm(touched)
        return True

    def confirm(self, seqs: dict[str, int]) -> None:
        """Tell the leader how far each space is installed here."""
        message = pack({"store": str(self.session.zid()), "seqs": seqs})
        self.session.put(
            f"{self.root}/@repl/ack", message, congestion_control=zenoh.CongestionControl.BLOCK
        )

    def _fetch(self, state: SpaceState, last: int) -> bool:
        """Install the leader's changesets after `state.seq` up to `last`, or copy the space.

        Returns False when the leader did not answer.
        """
        if last < state.seq:
            return self._copy(state.name)  # this store holds changes the leader never made
        if not state.seq and not last:
            return True
        key = keys.service_key(state.name, "log", self.root)
        # From this store's own last changeset on: the leader's must be the same one.
        request = pack({"from": max(state.seq, 1), "to": last})
        try:
            changes = ask_store(self.session, key, request, 10.0, what="log request")["changes"]
        except SpaceError as exc:
            log.warning("could not catch up %s: %s", state.name, exc)
            return False
        payloads = [bytes(p) for p in changes]
        if state.seq:
            theirs = Changeset.decode(payloads.pop(0)) if payloads else None
            if theirs is None or theirs.seq != state.seq or theirs.id != self._own_last(state):
                return self._copy(state.name)
        if payloads and Changeset.decode(payloads[0]).seq != state.seq + 1:
            return self._copy(state.name)  # the leader's log no longer reaches back to this store
        self._install(state, payloads)
        return True

    def _own_last(self, state: SpaceState) -> str | None:
        rows = self.db.log(state.name, state.seq, state.seq)
        return Changeset.decode(rows[0][1]).id if rows else None

    def _copy(self, name: str) -> bool:
        """Replace this store's copy of a space with the leader's whole state.

        Returns False when the leader did not answer.
        """
        key = f"{self.root}/@repl/state"
        try:
            reply = ask_store(self.session, key, pack({"space": name}), 30.0, what="state copy")
        except SpaceError as exc:
            log.warning("could not copy %s from the leader: %s", name, exc)
            return False
        seq, last = int(reply["seq"]), bytes(reply["last"])
        if not seq:
            return True  # the leader holds nothing of it
        rows = [tuple(str(x) for x in row) for row in reply["rows"]]
        prefixes = {str(k): str(v) for k, v in reply["prefixes"].items()}
        try:
            self.db.replace(name, rows, prefixes, (seq, last))  # type: ignore[arg-type]
        except CommitFailed as exc:
            log.error("could not store the copy of %s: %s", name, exc)
            return False
        self.forget(name)  # the next use loads it from the database
        log.warning("space %s copied whole from the leader (seq %d, %d rows)", name, seq, len(rows))
        return True

    def _install(self, state: SpaceState, payloads: list[bytes]) -> None:
        """Commit the leader's changesets that continue this store's copy, in one update.

        A failed commit leaves this copy as the database has it (the state is reloaded).
        """
        entries = []
        for payload in payloads:
            if Changeset.decode(payload, published=True).seq == state.seq + 1:
                entries.append(state.install(payload).entry)
        try:
            self.db.commit(entries)
        except CommitFailed as exc:
            log.error("could not install the leader's changes to %s: %s", state.name, exc)
            self.forget(state.name)
            return
        state.settle()
