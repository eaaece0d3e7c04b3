"""One lifecycle for every agent process, after py_trees' behaviours.

An agent is constructed without side effects; `setup()` opens the space,
declares the agent's liveliness token and rebuilds its view (snapshot, then
every change after it, with no gap); `run()` delivers changes on the agent's
own thread (`TripleSpace.deliver`: no dispatcher thread between Zenoh and
the agent) and ticks the agent until `stop()`; `shutdown()` closes everything
in reverse order. Zenoh callbacks only enqueue, so nothing ever blocks inside Zenoh.
`run_agent(cls, argv)` (`agents.process`) is the `__main__` of every `agents/NAME.py`.
"""

from __future__ import annotations

import argparse
import logging
import queue
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import ClassVar

import zenoh
from rdflib import URIRef
from rdflib.term import Node

from agents.process import build_parser as build_parser
from agents.process import run_agent as run_agent
from agents.view import View
from agents.vocabulary import local_name, robot_iri
from agents.writes import Writes
from space import (
    Change,
    MirrorReads,
    SpaceError,
    SpaceTimeout,
    SpaceUnavailable,
    Subscription,
    TripleSpace,
    declare_agent,
    identity_of,
)

Values = Mapping[tuple[Node, Node], Node | None]


class SimClock:
    """Simulated seconds: wall time since construction times `scale`.

    Drivers integrate over simulated time so that tests and scenarios can run
    a battery's hour in seconds with `--time-scale`.
    """

    def __init__(self, scale: float = 1.0) -> None:
        self.scale = scale
        self._start = time.monotonic()

    def now(self) -> float:
        """Return the simulated seconds elapsed."""
        return (time.monotonic() - self._start) * self.scale


class Agent:
    """Base of every agent process: subclasses override the hooks at the end.

    Attributes:
        kind: the agent's kind, the first part of its default name.
        per_robot: False for agents serving the whole space (named just `kind`).
        keeps_view: False for agents that never read `view` (it is then left empty:
            applying a 600-triple change to it costs milliseconds).
        shared: for a per-robot agent, the predicates it follows on any subject besides
            its robot's own subjects (`ac:robot7`, `ac:robot7_*`): it then receives only
            those parts of the space's changes, the router filtering out the rest of a
            fleet's traffic (`TripleSpace.subscribe(scope=...)`). None: every change.
        ticks_on_reads: True for an agent that decides in `tick` from its view alone: a
            change then wakes the tick only when it adds or removes a triple of a
            (subject, predicate) the last tick read (`SpaceMirror.reading`; the values it
            writes are read too, by `set_values`), never when it is the agent's own write
            coming back. False: every batch of changes wakes it.
        args: the parsed command line.
        robot: the robot this agent serves.
        name: the agent's name in logs, liveliness and changesets.
        view: the agent's local copy of the space.
        ts: the space, once `setup()` opened it.
    """

    kind: ClassVar[str] = "agent"
    per_robot: ClassVar[bool] = True
    keeps_view: ClassVar[bool] = True
    shared: ClassVar[tuple[URIRef, ...] | None] = None
    ticks_on_reads: ClassVar[bool] = False

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.robot = robot_iri(args.robot)
        default = f"{self.kind}.{local_name(self.robot)}" if self.per_robot else self.kind
        self.name: str = args.name or default
        self.log = logging.getLogger(self.name)
        self.clock = SimClock(args.time_scale)
        self.view = View()
        self.writes = Writes()
        self.ts: TripleSpace | None = None
        self.started = False
        self._token: zenoh.LivelinessToken | None = None
        self._subscription: Subscription | None = None
        self._inbox: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()  # before `ts`
        self._changed = False  # whether what was delivered since the last tick calls for one
        self._stop = threading.Event()
        self._early: list[Callable[[], None]] = []
        self._leased: dict[tuple[Node, Node], Node] = {}  # values set, renewed while alive
        self._next_renewal = 0.0
        self._reads: MirrorReads | None = None  # what the last tick read (`ticks_on_reads`)

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add the agent's own options to its parser (none by default)."""

    # Lifecycle

    def setup(self) -> None:
        """Open the space, declare liveliness, subscribe with a snapshot.

        Blocks until a router and the store answer, retrying for `--wait`
        seconds (agents may start before `tspace serve`) or until `stop()`.

        Raises:
            SpaceUnavailable: no router or no store within `--wait` seconds.
        """
        deadline = time.monotonic() + self.args.wait
        while True:
            try:
                if self.ts is None:
                    self.ts = TripleSpace.open(
                        self.args.connect,
                        space=self.args.space,
                        agent=self.name,
                        config_file=self.args.config,
                        identity=identity_of(self.args, self.name),
                        lifespan=self.args.lifespan,
                        dispatch_thread=False,  # `run` delivers
                    )
                    self._token = declare_agent(self.ts.session, self.ts.space, self.name)
                self._subscription = self.subscribe()
                break
            except (SpaceUnavailable, SpaceTimeout) as exc:
                if time.monotonic() >= deadline or self._stop.is_set():
                    raise SpaceUnavailable(f"no store within {self.args.wait} s: {exc}") from exc
                self.log.info("waiting for the space: %s", exc)
                self._stop.wait(0.5)
        self.log.info("connected to space %r as %s", self.ts.space, self.name)

    def scope(self) -> list[tuple[object, object]] | None:
        """Return the (subject, predicate) pairs this agent follows; None for the whole space."""
        if self.shared is None or not self.per_robot:
            return None
        return robot_scope(self.robot, self.shared)

    def subscribe(self) -> Subscription:
        """Subscribe to the space; the first change delivered is the snapshot.

        A scoped agent's snapshot is the whole space but other robots' parts
        (`View.concerning`): what it knows once of the site, its robot's state.
        Blocking; called by `setup()`. The reasoner overrides it to load the
        asserted graph on its own.
        """
        assert self.ts is not None
        scope = self.scope()
        return self.ts.subscribe(
            None,
            self._receive,
            snapshot="all" if scope is not None else True,
            timeout=self.args.timeout,
            scope=scope,
        )

    def run(self) -> None:
        """Handle changes and tick until `stop()`.

        A tick follows every batch of changes at once (the changes waiting are
        applied first; with `ticks_on_reads`, a batch of which one concerns the
        tick), so an agent acts on a conclusion in milliseconds, not at its next
        period; without changes it ticks every `--tick` seconds.
        """
        assert self.ts is not None
        next_tick = time.monotonic()
        while not self._stop.is_set():
            while not self._inbox.empty():  # work handed over before the space was open
                self.call_soon(self._inbox.get())
            self._changed = False
            if not self.ts.deliver(max(0.0, next_tick - time.monotonic())):
                return  # closed
            self._surface_failed_writes()
            if self.started and (self._changed or time.monotonic() >= next_tick):
                self._guarded(self._tick, "tick")
                self._guarded(self._renew, "renewal")
                next_tick = time.monotonic() + self.args.tick
            elif not self.started:
                next_tick = time.monotonic() + self.args.tick

    def stop(self) -> None:
        """Make `run()` return soon; safe from a signal handler or another thread."""
        self._stop.set()
        self.call_soon(lambda: None)  # wakes `run()`

    def call_soon(self, work: Callable[[], None]) -> None:
        """Run `work` on the loop's thread soon, then tick; safe from any thread.

        What a Zenoh callback must not do itself (write to the space, call a
        service) it hands over so. Work before the view is rebuilt waits for it.
        """
        ts = self.ts
        if ts is None:
            self._inbox.put(work)  # posted once the space is open
        else:
            ts.post(lambda: self._receive(work))

    def shutdown(self) -> None:
        """Settle the writes in flight, close the subscription, the token and the space."""
        try:
            self.writes.close(self.args.timeout)
            if self._subscription is not None:
                self._subscription.close()
            if self._token is not None:
                self._token.undeclare()
        finally:
            if self.ts is not None:
                self.ts.close()
            self._subscription, self._token, self.ts = None, None, None

    # Handling

    def _receive(self, change: Change | Callable[[], None]) -> None:
        """Take a change or work delivered on the loop's thread (within `run`'s `deliver`)."""
        self._changed |= self._handle(change)

    def _handle(self, change: Change | Callable[[], None]) -> bool:
        """Handle a change or work; return whether a tick should follow."""
        if not isinstance(change, Change):
            if self.started:
                self._guarded(change, "work")
            else:
                self._early.append(change)
            return True
        wakes = self._wakes(change)
        if self.keeps_view:
            if not self.started and self.shared is not None:
                change.added = View.concerning(change.added, self.robot)
            self.view.apply(change, snapshot=not self.started)
        if not self.started:
            self.started = True
            self.log.info("view rebuilt from the space: %d triples", len(self.view))
            if self.shared is not None and (strays := self.view.strays(self.robot)):
                self.log.warning(
                    "not named after %s, so their changes never reach this agent: %s",
                    local_name(self.robot),
                    ", ".join(local_name(s) for s in strays),  # type: ignore[arg-type]
                )
            self._guarded(self.on_start, "start")
            while self._early:
                self._guarded(self._early.pop(0), "work")
        else:
            self._guarded(lambda: self.on_change(change), f"change {change.id}")
        return wakes

    def _wakes(self, change: Change) -> bool:
        """Return whether `change` concerns the tick (`ticks_on_reads`); always before a tick."""
        if not self.ticks_on_reads or self._reads is None:
            return True
        return change.agent != self.name and self._reads.touched_by(change)

    def _tick(self) -> None:
        """Tick, noting what it read when a change wakes it only if it concerns that."""
        if not self.ticks_on_reads:
            self.tick()
            return
        self._reads = None  # a tick that fails half-way read an unknown part: every change wakes
        with self.view.reading() as reads:
            self.tick()
        self._reads = reads

    def _guarded(self, step: Callable[[], None], what: str) -> None:
        """Run one step; what comes from the network may be malformed: log it, go on."""
        try:
            step()
        except SpaceError as exc:
            self.log.warning("%s: %s", what, exc)
        except Exception:
            self.log.exception("%s failed, skipped", what)

    # Writing

    def set_values(
        self, values: Values, *, cause: str | None = None, wait: bool = False
    ) -> str | None:
        """Write single-valued states as one changeset; return its id, None if nothing changed.

        `values` maps (subject, predicate) to the new object (None removes the
        state). The view is updated at once so the next tick sees it. Returns as
        soon as the changeset is sent: its acknowledgement is read off the loop,
        and a write the store did not take is undone in the view and logged
        (`_surface_failed_writes`). With `wait` (a person waiting for the answer,
        as the HMI's commands), blocks until the store made it durable instead.

        Raises:
            SpaceError: with `wait`, the store did not take it (the view is left as it was).
        """
        assert self.ts is not None
        added, removed = [], []
        if self.args.lifespan:
            for (s, p), o in values.items():
                if o is None:
                    self._leased.pop((s, p), None)
                else:
                    self._leased[(s, p)] = o
        for (s, p), o in values.items():
            old = self.view.objects(s, p)
            if o is not None and old == [o]:
                continue
            removed += [(s, p, x) for x in old if x != o]
            if o is not None and o not in old:
                added.append((s, p, o))
        if not added and not removed:
            return None
        self.view.remove(removed)
        self.view.add(added)
        cs = self.ts.changeset(added, removed, cause=cause)
        if not wait:
            self.writes.track(
                cs.id, self.ts.send_later(cs, timeout=self.args.timeout), added, removed
            )
            return cs.id
        try:
            return self.ts.send(cs, timeout=self.args.timeout)
        except SpaceError:
            self.view.remove(added)
            self.view.add(removed)
            raise

    def _surface_failed_writes(self) -> None:
        """Undo in the view, and log, each write the store did not take (the loop's thread)."""
        for failed in self.writes.failed():
            if not failed.added and not failed.removed:  # a renewal (`_renew`): nothing to undo
                self.log.warning("renewal %s not taken: %s", failed.id, failed.error)
                continue
            unknown = isinstance(failed.error, SpaceUnavailable | SpaceTimeout)  # no answer came
            what = "unanswered, maybe applied" if unknown else "not taken"
            self.log.warning("write %s %s, undone in the view: %s", failed.id, what, failed.error)
            if all(t in self.view for t in failed.added):
                self.view.remove(failed.added)
                self.view.add(failed.removed)

    def _renew(self) -> None:
        """Write again, every third of `--lifespan`, the values this agent set and still holds.

        So they live as long as the agent does, and expire a lifespan after it
        dies or is cut off (the store retracts them; the rules see it).
        """
        if not self.args.lifespan or time.monotonic() < self._next_renewal:
            return
        assert self.ts is not None
        self._next_renewal = time.monotonic() + self.args.lifespan / 3
        held = [(s, p, o) for (s, p), o in self._leased.items() if o in self.view.objects(s, p)]
        if held:  # pipelined like every write; a renewal not taken is only logged
            cs = self.ts.changeset(held)
            self.writes.track(cs.id, self.ts.send_later(cs, timeout=self.args.timeout), [], [])

    # Hooks

    def on_start(self) -> None:
        """React to the rebuilt view, once, before the first tick."""

    def on_change(self, change: Change) -> None:
        """React to a change of the space (already applied to the view)."""

    def tick(self) -> None:
        """Advance simulations and controllers; called every `--tick` seconds. Never blocks long."""


def robot_scope(robot: URIRef, shared: Sequence[URIRef] = ()) -> list[tuple[object, object]]:
    """Return the scope of a robot's agent: its robot, the robot's parts, `shared` predicates.

    A robot's parts are named after it (`ac:robot7_battery`, as `agents.sim.fleet`
    names the clones), which is what lets the router select them by key.
    """
    return [(robot, None), (f"{robot}_*", None), *((None, p) for p in shared)]
