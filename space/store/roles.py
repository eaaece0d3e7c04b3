"""A store's role among the stores holding the same spaces: lead, or follow the leader.

Several stores may hold the same spaces (see docs/deployment.md): the one
alive the longest leads (sequences writes, answers reads); the others follow
the leader's changes, and the follower with the smallest Zenoh id takes over
when the leader's liveliness token goes away. A follower announces itself
(`@stores/<zid>`: acknowledged as a replica, a candidate to take over) only
once it has caught up with the leader; one that could not stays silent and
retries.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

import zenoh

from space.store.acks import AckGate
from space.store.replica import Replica

log = logging.getLogger("tspace.store")

CATCH_UP_RETRY = 1.0  # seconds between a follower's attempts to catch up with the leader


class Roles:
    """Decide whether a store leads or follows, and change role as stores come and go.

    `open` and `close` run on the server's caller's thread; everything else
    on the store's worker thread only, which alone touches state and database.

    Args:
        leading: declare what a leader serves (the store's queryables and subscribers).
        following: declare what a follower listens to (the leader's changes).
        seqs: each space's sequence number, to confirm to the leader once caught up.
    """

    def __init__(
        self,
        session: zenoh.Session,
        root: str,
        acks: AckGate,
        *,
        look_for_leader: float,
        leading: Callable[[], list],
        following: Callable[[], list],
        seqs: Callable[[], dict[str, int]],
    ) -> None:
        self.session = session
        self.root = root
        self.look_for_leader = look_for_leader
        self.zid = ""
        self.role = ""
        self.leader = ""
        self.ready = threading.Event()  # set once this store leads or has caught up
        self._acks = acks
        self._leading = leading
        self._following = following
        self._seqs = seqs
        self._replica: Replica
        self._watchers: list = []
        self._entities: list = []
        self._token: zenoh.LivelinessToken | None = None
        self._stores: set[str] = set()
        self._behind_until: float | None = None  # a follower behind: when to try again

    def open(
        self, replica: Replica, on_peer: Callable[[str], Callable[[zenoh.Sample], None]]
    ) -> None:
        """Watch the other stores' tokens; `on_peer` must hand what they say to `peer`."""
        self._replica = replica
        self.zid = str(self.session.zid())
        live = self.session.liveliness()
        self._watchers = [
            live.declare_subscriber(f"{self.root}/@stores/*", on_peer("store"), history=True),
            live.declare_subscriber(f"{self.root}/@leader/*", on_peer("leader"), history=True),
        ]

    def close(self) -> None:
        """Undeclare everything the role declared, then this store's token."""
        for entity in reversed([*self._watchers, *self._entities]):
            entity.undeclare()
        self._watchers, self._entities = [], []
        self._silence()

    def decide(self) -> None:
        """Follow a leading store if one answers within `look_for_leader` seconds, else lead.

        Blocks that long at most, and while a follower catches up.
        """
        deadline = time.monotonic() + self.look_for_leader
        while True:
            replies = self.session.liveliness().get(f"{self.root}/@leader/*", timeout=0.5)
            leaders = sorted(
                zid
                for r in replies
                if r.ok is not None and (zid := str(r.ok.key_expr).rsplit("/", 1)[1]) != self.zid
            )
            if leaders:
                self._follow(leaders[0])
                return
            if time.monotonic() >= deadline:
                self._lead()
                return
            time.sleep(0.1)

    def retry(self) -> None:
        """Try again to catch up with the leader, if behind and the time has come (blocks)."""
        if self._behind_until is not None and time.monotonic() >= self._behind_until:
            self._catch_up()

    def follow(self, published: list[tuple[str, bytes]]) -> None:
        """Install changesets the leader published, `(space, payload)`, if following.

        A follower behind ignores them: its next catch-up fetches them from the log.
        """
        if self.role == "following" and self._behind_until is None:
            if not self._replica.follow(published):
                self._fall_behind()

    def peer(self, what: str, zid: str, alive: bool) -> None:
        """Take note of a store's (`what="store"`) or leader's token coming or going."""
        if what == "store":
            if alive:
                self._stores.add(zid)
                if zid != self.zid:
                    self._acks.candidates.add(zid)  # waited for once it confirms a change
            else:
                self._stores.discard(zid)
                self._acks.forget(zid)
            return
        if alive and zid != self.zid:
            if self.role == "leading" and zid < self.zid:
                if not self._is_store(zid):
                    log.warning("ignoring a leader token %s that no store answers for", zid)
                    return
                log.warning("store %s also leads; %s steps down", zid, self.zid)
                self._follow(zid)
            elif self.role == "following":
                self.leader = zid
        elif not alive and zid == self.leader and self.role == "following":
            if self._behind_until is not None:
                # Its copy may lack acknowledged changes: no answer beats a wrong one.
                log.error("leader %s is gone before this store caught up: not taking over", zid)
                return
            candidates = sorted((self._stores - {zid}) | {self.zid})
            if candidates[0] == self.zid:
                log.warning("leader %s is gone; store %s takes over", zid, self.zid)
                self._lead()

    def _is_store(self, zid: str) -> bool:
        """Return whether the session `zid` answers as a store (a token alone proves nothing).

        Blocks up to a second. Anyone may declare a liveliness token on
        `@leader/...`; only a store's own session answers `@repl/spaces`.
        """
        replies = self.session.get(f"{self.root}/@repl/spaces", timeout=1.0)
        return any(r.ok is not None and str(r.replier_id) == zid for r in replies)

    def _declare(self, entities: list) -> None:
        for entity in reversed(self._entities):
            entity.undeclare()
        self._entities = entities

    def _lead(self) -> None:
        entities = self._leading()
        entities.append(self.session.liveliness().declare_token(f"{self.root}/@leader/{self.zid}"))
        self._declare(entities)
        self.role, self.leader = "leading", self.zid
        self._behind_until = None
        self._acks.followers = set()
        self._acks.candidates = self._stores - {self.zid}
        self._announce()
        self.ready.set()
        log.info("store %s leads", self.zid)

    def _follow(self, leader: str) -> None:
        self._declare(self._following())
        self.role, self.leader = "following", leader
        self._acks.followers = set()
        self._silence()  # a leader stepping down is not a replica until it has caught up
        self._catch_up()

    def _catch_up(self) -> None:
        """Fetch what this store missed from the leader; announce it then, or retry later."""
        if not self._replica.catch_up():
            self._fall_behind()
            return
        self._behind_until = None
        self._announce()
        self.ready.set()
        log.info("store %s follows %s", self.zid, self.leader)

    def _fall_behind(self) -> None:
        """Stay silent (no replica, no candidate to lead) and try to catch up again soon."""
        if self._behind_until is None:
            log.warning(
                "store %s could not catch up with the leader: silent, retrying every %g s",
                self.zid,
                CATCH_UP_RETRY,
            )
        self._silence()
        self._behind_until = time.monotonic() + CATCH_UP_RETRY

    def _silence(self) -> None:
        if self._token is not None:
            self._token.undeclare()
            self._token = None

    def _announce(self) -> None:
        if self._token is None:
            self._token = self.session.liveliness().declare_token(f"{self.root}/@stores/{self.zid}")
        if self.role == "following":
            self._replica.confirm(self._seqs())
