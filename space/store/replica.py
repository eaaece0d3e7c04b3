"""A follower store's side of replication: catch up from the leader, then follow it.

The leader's net changesets (what it publishes on `@/changes` and keeps in its
log) are installed exactly, in sequence order; a gap is filled from the
leader's log; each install is confirmed on `@repl/ack` so the leader can
acknowledge writes that every replica holds.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import zenoh

from space import keys
from space.changeset import Changeset, pack
from space.errors import MalformedPayload, SpaceError
from space.request import ask_store
from space.store.db import StoreDB
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
    ) -> None:
        self.session = session
        self.root = root
        self.db = db
        self.space = space

    def catch_up(self) -> None:
        """Fetch from the leader what this store missed, space by space (blocks)."""
        try:
            reply = ask_store(self.session, f"{self.root}/@repl/spaces", b"", 5.0, what="sync")
        except SpaceError as exc:
            log.warning("could not ask the leader for its spaces: %s", exc)
            return
        for name, seq in reply.items():
            self._fetch(self.space(str(name)), int(seq))

    def follow(self, published: list[tuple[str, bytes]]) -> None:
        """Install changesets the leader published, `(space, payload)`, and confirm them."""
        touched: dict[str, int] = {}
        for space, payload in published:
            try:
                net = Changeset.decode(payload)
            except MalformedPayload as exc:
                log.warning("malformed replicated change on %r skipped: %s", space, exc)
                continue
            state = self.space(space)
            if net.seq > state.seq + 1:
                self._fetch(state, net.seq - 1)
            if net.seq == state.seq + 1:
                self._install(state, [payload])
            touched[space] = state.seq
        if touched:
            self.confirm(touched)

    def confirm(self, seqs: dict[str, int]) -> None:
        """Tell the leader how far each space is installed here."""
        message = pack({"store": str(self.session.zid()), "seqs": seqs})
        self.session.put(
            f"{self.root}/@repl/ack", message, congestion_control=zenoh.CongestionControl.BLOCK
        )

    def _fetch(self, state: SpaceState, last: int) -> None:
        if last <= state.seq:
            return
        key = keys.service_key(state.name, "log", self.root)
        request = pack({"from": state.seq + 1, "to": last})
        try:
            changes = ask_store(self.session, key, request, 10.0, what="log request")["changes"]
        except SpaceError as exc:
            log.warning("could not catch up %s: %s", state.name, exc)
            return
        self._install(state, [bytes(p) for p in changes])

    def _install(self, state: SpaceState, payloads: list[bytes]) -> None:
        commits = []
        for payload in payloads:
            net = Changeset.decode(payload)
            if net.seq == state.seq + 1:
                commits.append(state.install(net, payload))
        if commits:
            self.db.commit(commits)
