"""The HMI agent: a web page where a person watches the robots and tells them what to do.

The page shows each robot's task, place, battery, speed, what it says, its
devices' commanded and reported modes, its battery and speed plotted over time
and a timeline of tasks and device modes with the rule firings on it, each
firing said as a sentence with its `why` one click away; live (server-sent
events). The history comes from the space (`agents.hmi_history`: the store's
changeset log at start, then every change), so a reload or a restart of the
HMI shows it again. A person can request a task (`ac:requested_task`, which
the behaviour agent turns into the current task) and, in simulation, set the
battery level. The HTTP server runs on its own threads and never touches the
space: the agent's thread publishes the state to it after each change and runs
its commands (and `why` questions) on tick.

Run: `python -m agents.hmi --connect tcp/127.0.0.1:7447 --space hospital --http-port 8080`.
"""

from __future__ import annotations

import argparse
import sys
import threading
from collections import deque
from dataclasses import asdict

from rdflib import OWL, RDF, RDFS, Literal, URIRef
from rdflib.term import Node

from agents.base import Agent, run_agent
from agents.hmi_freshness import Freshness
from agents.hmi_history import LOOKBACK, History
from agents.hmi_web.guard import Guard
from agents.hmi_web.server import CommandError, Commands, HmiServer, StateBoard
from agents.runtime.robotview import BadValues, read_firings, read_robots
from agents.sim.battery import middle_of
from agents.vocabulary import AC, local_name
from space import (
    Change,
    ChangeRecord,
    ClusterWatch,
    MalformedPayload,
    PrefixMap,
    Template,
    Triple,
    from_nt,
    triple_text,
)

TASK_TYPES = ("AttendingPatient", "Guiding", "GoingToDock", "Idle")
PREFIXES = PrefixMap({"ac": str(AC), "rdf": str(RDF), "rdfs": str(RDFS), "owl": str(OWL)})
WHY_LIMIT = 10


class Hmi(Agent):
    """Serve the HMI web page for every robot of the space."""

    kind = "hmi"

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.board = StateBoard()
        self.commands = Commands()
        self.records: deque[ChangeRecord] = deque(maxlen=200)
        self.bad_values = BadValues(self.log.warning)
        self.history = History()
        self.freshness = Freshness()
        self._new_events: list[dict] = []
        self.server: HmiServer | None = None
        self._http: threading.Thread | None = None
        self.cluster: ClusterWatch | None = None  # replicas' quorum, in cluster mode
        self._cluster_line = ""

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add `--http-host` and `--http-port`."""
        parser.add_argument(
            "--http-port", type=int, default=8080, help="port of the web page (default 8080)"
        )
        parser.add_argument(
            "--http-host", default="127.0.0.1", help="address to serve on (default 127.0.0.1)"
        )

    def setup(self) -> None:
        """Start serving the page, then connect to the space (the page says when it is up).

        Raises:
            SystemExit: the port is taken.
            SpaceUnavailable: see `Agent.setup`.
        """
        address = (self.args.http_host, self.args.http_port)
        try:
            guard = Guard([self.args.http_host])
            self.server = HmiServer(address, self.board, self.commands, self.log.debug, guard)
        except OSError as exc:
            raise SystemExit(f"hmi: cannot serve on {address[0]}:{address[1]}: {exc}") from exc
        self._http = threading.Thread(
            target=self.server.serve_forever, name="hmi-http", daemon=True
        )
        self._http.start()
        self.log.info("HMI at http://%s:%d/", address[0], self.server.port)
        super().setup()

    def shutdown(self) -> None:
        """End the event streams, stop the web server, then leave the space."""
        try:
            if self.cluster is not None:
                self.cluster.close()
                self.cluster = None
            self.board.close()
            if self.server is not None:
                if self._http is not None:
                    self.server.shutdown()
                self.server.server_close()
        finally:
            self.server, self._http = None, None
            super().shutdown()

    def on_start(self) -> None:
        """Rebuild the history from the store's log, then show the state the space has now."""
        assert self.ts is not None
        if self.cluster is None:
            self.cluster = ClusterWatch(self.ts.session)
        seq = self.ts.seq(timeout=self.args.timeout)
        changes, _ = self.ts.history(max(1, seq - LOOKBACK + 1), seq, timeout=self.args.timeout)
        self._new_events = self.history.events(changes, self.view.graph)
        self.log.info("history: %d events from %d changesets", len(self._new_events), len(changes))
        self._publish()

    def on_change(self, change: Change) -> None:
        """Remember the change (its events, and to explain later firings); show the new state."""
        self.records.append(ChangeRecord.of(change))
        self.freshness.note(change)
        self._new_events += self.history.events([change], self.view.graph)
        self._publish()

    def tick(self) -> None:
        """Run the commands the page sent since the last tick; tell the page of renewals."""
        self.commands.run_pending(self._command)
        line = self.cluster.line() if self.cluster is not None else ""
        if line != self._cluster_line:  # first: a minority side's reads below fail
            self._cluster_line = line
            self._publish()
        assert self.ts is not None
        if self.freshness.poll(self.ts, self.args.timeout):
            self._publish()

    def _publish(self) -> None:
        graph = self.view.graph
        robots = []
        for robot in read_robots(graph, self.bad_values):
            iri = AC[robot.name]
            site = self.view.value(iri, AC.site)
            state = asdict(robot)
            for device in state["devices"]:
                device["reported"] = self.view.text(AC[device["name"]], AC.actual_mode)
                device["reported_fresh"] = self.freshness.of(AC[device["name"]], AC.actual_mode)
            battery = self.view.device(iri, AC.Battery)
            state.update(
                site=local_name(site) if isinstance(site, URIRef) else None,
                presence=self.view.text(iri, AC.presence),
                people=self._named(site, AC.Person, AC.Patient),
                places=self._named(site, AC.Room, AC.Corridor, AC.Dock),
                battery_fresh=self.freshness.of(battery, AC.battery_level),
            )
            robots.append(state)
        events, self._new_events = self._new_events, []
        self.board.publish(
            {
                "connected": True,
                "space": self.args.space,
                "robots": robots,
                "firings": [asdict(f) for f in read_firings(self.records)],
                "tasks": [t for t in TASK_TYPES if self.view.task_of_type(t) is not None],
                "levels": self._levels(),
                "cluster": self.cluster.statuses() if self.cluster is not None else [],
            },
            events,
        )

    def _named(self, site: Node | None, *classes: URIRef) -> list[dict[str, str]]:
        """Return the individuals of `classes` on `site` as {"name", "label"}, sorted by name.

        A person's site is their room's; with no site, every individual of the classes.
        """
        found = {i for c in classes for i in self.view.graph.subjects(RDF.type, c)}
        if site is not None:
            found = {i for i in found if site in (self._site_of(i), None)}
        return [
            {"name": local_name(i), "label": self.view.text(i, RDFS.label) or local_name(i)}
            for i in sorted(found)
            if isinstance(i, URIRef)
        ]

    def _site_of(self, individual: Node) -> Node | None:
        site = self.view.value(individual, AC.site)
        room = self.view.value(individual, AC.room)
        return site if site is not None or room is None else self.view.value(room, AC.site)

    def _levels(self) -> list[str]:
        """Return the battery levels the integrator defined, emptiest first."""
        levels = self.view.levels(AC.BatteryLevel, AC.below_percent)
        return sorted(levels, key=levels.__getitem__)

    def _request_task(self, robot: URIRef, params: dict) -> str | None:
        """Request a task, with whom it is for and where to guide them if given."""
        task = self.view.task_of_type(str(params.get("task", "")))
        if task is None:
            raise CommandError(f"no task of type {params.get('task')!r} in the space")
        values: dict[tuple[Node, Node], Node | None] = {(robot, AC.requested_task): task}
        for key, predicate in (
            ("person", AC.attended_person),
            ("destination", AC.guide_destination),
        ):
            if params.get(key):
                individual = AC[str(params[key])]
                if not self.view.objects(individual, RDF.type):
                    raise CommandError(f"no {key} {params[key]!r} in the space")
                values[(robot, predicate)] = individual
        return self.set_values(values, wait=True)

    def _command(self, name: str, params: dict) -> str | None:
        """Carry out a command from the page; return the changeset id (None: no change).

        Raises:
            CommandError: unknown robot, task or level.
            SpaceError: the store did not take the change.
        """
        if name == "why":
            return self._why(params.get("templates") or [])
        robot = AC[str(params.get("robot", ""))]
        if not self.view.objects(robot, AC.has_device):
            raise CommandError(f"no robot {params.get('robot')!r} in the space")
        if name == "task":
            return self._request_task(robot, params)
        level = str(params.get("level", ""))
        thresholds = self.view.levels(AC.BatteryLevel, AC.below_percent)
        battery = self.view.device(robot, AC.Battery)
        if level not in thresholds or battery is None:
            raise CommandError(f"cannot set the battery of {params.get('robot')!r} to {level!r}")
        # A charge in the middle of the level: the hw_monitor adopts it as the battery's.
        return self.set_values(
            {
                (battery, AC.battery_level): Literal(level),
                (battery, AC.charge_percent): Literal(middle_of(level, thresholds)),
            },
            wait=True,
        )

    def _why(self, templates: list) -> list[dict]:
        """Return the explanations of what each template (N-Triples or None) matches, as JSON.

        Raises:
            CommandError: a term is not N-Triples.
            NoReasoner: no reasoner answered.
        """
        assert self.ts is not None

        def text(triple: Triple) -> str:
            return triple_text(triple, PREFIXES)

        out = []
        for wire in templates:
            try:
                template = Template(*(None if t is None else from_nt(str(t)) for t in wire))
            except MalformedPayload as exc:
                raise CommandError(str(exc)) from exc
            trees = self.ts.why(template, limit=WHY_LIMIT, timeout=self.args.timeout)
            out += [tree.to_json(text) for tree in trees]
        return out


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the HMI agent (see `--help`)."""
    return run_agent(Hmi, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
