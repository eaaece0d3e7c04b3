"""Watching a space: subscriptions, and catching up on what a cut link missed."""

from __future__ import annotations

import logging
from collections.abc import Callable

import zenoh
from zenoh import ext

from space import keys
from space._handle import Handle, TemplateLike, _triples
from space._scope import Scope, selectors
from space._scoped import ScopedSubscription
from space._subscription import Callback, Change, Subscription
from space.changeset import unpack
from space.errors import InputError, MalformedPayload

log = logging.getLogger("tspace.client")


class Watching(Handle):
    """The subscribe side of `TripleSpace`."""

    def subscribe(
        self,
        template: TemplateLike,
        callback: Callback,
        *,
        snapshot: bool | str = False,
        timeout: float = 5.0,
        skip_own: bool = False,
        scope: list[Scope] | None = None,
        texts: bool = False,
    ) -> Subscription:
        """Call `callback(change)` for every later changeset with triples matching `template`.

        With `snapshot=True` the first call carries the current matching state.
        Callbacks run in this handle's dispatcher thread, one at a time, in store order.
        `skip_own` leaves out the changesets this handle's agent wrote before
        their terms are parsed (a big change costs nothing to ignore).

        `scope`, (subject, predicate) pairs (each None, a term, or `"IRI-prefix*"`:
        `[(AC.robot7, None), ("ac:robot7_*", None)]`), asks only for the triples
        of those subjects and predicates: the router sends nothing else, so a
        robot's agent does not even receive the rest of a fleet's traffic. A
        changeset then comes in parts, by subject and predicate: those that arrive
        together are delivered as one change, a late one as another with the same
        id and seq; parts of one key come in store order, with no gap. See
        docs/wire-format.md. Its snapshot holds the scope's state, or, with
        `snapshot="all"`, everything matching `template` (the knowledge a robot's
        agent reads once, whose changes do not concern it).

        `texts=True` (whole changesets only: no template, scope or snapshot) leaves
        the terms unparsed: each change's triples are their N-Triples texts `(s, p, o)`,
        checked for shape (`space.terms.text_triple`), for a reader that keeps terms
        in their wire form and parses one only when it first meets it (the reasoner's
        engine, `apply_texts`).

        Raises:
            SpaceUnavailable: no store answered (the sequence number is needed to fill gaps).
            InputError: a malformed scope; `texts` with a template, a scope or a snapshot.
        """
        t = self._template(template)
        if texts and (scope is not None or snapshot or (t.s, t.p, t.o) != (None, None, None)):
            raise InputError("texts=True is for whole changesets: no template, scope or snapshot")
        if not self._watchdogs:
            self._watch_store()
        skip_agent = self.agent if skip_own else None
        if scope is None:
            sub = Subscription(self._dispatcher, t, callback, skip_agent=skip_agent, texts=texts)
            sub_keys: list[str] = []  # whole changesets: an advanced subscriber, below
        else:
            sub = ScopedSubscription(
                self._dispatcher,
                t,
                callback,
                space=self.space,
                selectors=self._selectors(scope),
                skip_agent=skip_agent,
            )
            sub_keys = sub.keys
        self._dispatcher.add(sub)
        self._subscriptions.add(sub)
        try:
            if isinstance(sub, ScopedSubscription):  # ends first: none after a part is missed
                end = keys.end_key(self.space)
                sub.attach(self.session.declare_subscriber(end, sub.on_end(self.session)))
            for key in sub_keys:
                sub.attach(self.session.declare_subscriber(key, self._dispatcher.feed(sub)))
            if scope is None:
                sub.attach(self._whole(sub))
            if snapshot:
                reply = self._snapshot(t, timeout)
                seq = int(reply.get("seq") or 0)
                state = list(dict.fromkeys(_triples(reply)))
                if isinstance(sub, ScopedSubscription) and snapshot != "all":
                    state = [x for x in state if sub.selects(x)]
                initial = Change(
                    agent="",
                    seq=seq,
                    added=state,
                    bindings=[b for x in state if (b := t.match(x)) is not None],
                )
            else:
                seq, initial = self._seq(timeout), None
        except BaseException:
            self.unsubscribe(sub)
            raise
        if isinstance(sub, ScopedSubscription):
            sub.start(seq)
        self._dispatcher.mark_ready(sub, seq, initial)
        return sub

    def _whole(self, sub: Subscription) -> ext.AdvancedSubscriber:
        """Declare the Zenoh subscriber feeding `sub` the space's whole changesets.

        Whole changesets come from the store's advanced publisher (`space.store.publish`):
        an advanced subscriber that sees a gap in its sample numbers asks that publisher's
        cache for the missing ones and delivers in order, so our seq check does not have
        to ask the log. What the cache cannot give (a longer gap, another replica's
        changesets, a restarted store's) that seq check still fetches: it is the sample
        miss listener we need. `heartbeat=True` follows the store's sporadic heartbeat, so
        a lost last sample comes from the cache too (and Zenoh 1.10.2's Python API has no
        recovery without it or periodic queries). Parts keep a plain subscriber: the store
        would need an advanced publisher per part key, each 15 KB, a queryable and a
        heartbeat, for up to 200,000 keys a space (docs/performance.md).
        """
        recovery = ext.RecoveryConfig(periodic_queries=None, heartbeat=True)
        return ext.declare_advanced_subscriber(
            self.session, self._key("changes"), self._dispatcher.feed(sub), recovery=recovery
        )

    def _selectors(self, scope: list[Scope]) -> list[str]:
        try:
            return selectors(scope, self.prefixes)
        except InputError:
            self.load_prefixes()  # the prefix may be registered in the space
            return selectors(scope, self.prefixes)

    def _watch_store(self) -> None:
        """Fetch changes missed while a link was down from the store's log.

        On this session's reconnection, when the leading store's token comes back
        (a cut between it and us), and when the store's heartbeat shows a later
        sequence number, so a lost change shows up even when no later one follows.
        """
        self._watchdogs = [
            self.session.info.declare_transport_events_listener(self._on_transport),
            self.session.liveliness().declare_subscriber(
                f"{keys.ROOT}/@leader/*", self._on_transport
            ),
            self.session.declare_subscriber(self._key("seq"), self._on_heartbeat),
        ]

    def _on_transport(self, event: zenoh.TransportEvent | zenoh.Sample) -> None:
        if event.kind == zenoh.SampleKind.PUT:
            self._dispatcher.catch_up()

    def _on_heartbeat(self, sample: zenoh.Sample) -> None:
        try:
            beat = unpack(sample.payload.to_bytes())
            seq = int(beat["seq"])  # type: ignore[index]
        except (MalformedPayload, TypeError, KeyError, ValueError):
            log.warning("malformed heartbeat on %s skipped", sample.key_expr)
            return
        self._dispatcher.catch_up(seq)

    def deliver(self, timeout: float | None) -> bool:
        """Run the callbacks of the changes that arrive within `timeout` s (None: for ever).

        For a handle opened with `dispatch_thread=False`, whose owner calls it in its
        loop: the callbacks then run on the owner's thread. Returns as soon as what
        arrived is delivered (or, after `timeout`, nothing did); False once closed.
        """
        return self._dispatcher.deliver(timeout)

    def post(self, work: Callable[[], None]) -> None:
        """Run `work` where the callbacks run, after the changes already received; any thread."""
        self._dispatcher.post(work)

    def unsubscribe(self, sub: Subscription) -> None:
        """Stop a subscription."""
        sub.close()
        self._subscriptions.discard(sub)
