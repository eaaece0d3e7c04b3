"""The fleet monitor: which robots are present, from their agents' liveliness.

A robot whose host vanishes (power lost, network gone for good) says nothing;
Zenoh ends its agents' liveliness tokens when the lease of its link runs out
(10 s with `deploy/multihost/router.json5`). This agent turns that into a fact
the rules can use: `R ac:presence "present"` while at least one agent named
`KIND.R` (`hw_monitor.robot1`, ...) is alive, `"gone"` once none is. Only a
robot that was present becomes gone, so a robot that is described but not
started yet is left alone. Run one per space, on a host that is not a robot's
(next to the store): it must outlive the robots it watches.
"""

from __future__ import annotations

import argparse
import queue
import sys

import zenoh
from rdflib import RDF, Literal, URIRef

from agents.base import Agent, Values, run_agent
from agents.vocabulary import AC, local_name
from space import alive_agents, watch_agents

PRESENT = Literal("present")
GONE = Literal("gone")


def robot_of(agent: str) -> str | None:
    """Return the robot's local name in an agent's name `KIND.ROBOT`, None for a fleet agent."""
    _kind, dot, robot = agent.partition(".")
    return robot if dot and robot else None


class FleetMonitor(Agent):
    """Write each robot's presence (`ac:presence`) as its agents' liveliness comes and goes."""

    kind = "fleet_monitor"
    per_robot = False

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        self.alive: set[str] = set()
        self._events: queue.SimpleQueue[tuple[str, bool]] = queue.SimpleQueue()
        self._watcher: zenoh.Subscriber | None = None

    def setup(self) -> None:
        """Open the space (see `Agent.setup`), then watch the agents and learn who is alive.

        The watcher is declared before asking who is alive, so no arrival or
        departure falls between the two; replayed events change nothing.
        """
        super().setup()
        assert self.ts is not None
        self._watcher = watch_agents(
            self.ts.session, self.ts.space, lambda name, alive: self._events.put((name, alive))
        )
        self.alive = set(alive_agents(self.ts.session, self.ts.space, timeout=self.args.timeout))
        self.log.info("agents alive: %s", ", ".join(sorted(self.alive)) or "none")

    def shutdown(self) -> None:
        """Stop watching, then close the space (see `Agent.shutdown`)."""
        if self._watcher is not None:
            self._watcher.undeclare()
            self._watcher = None
        super().shutdown()

    def on_start(self) -> None:
        """Write the presence of the robots as the space and liveliness say it is now."""
        self._update()

    def tick(self) -> None:
        """Take in the arrivals and departures since the last tick; write what changed.

        Robots written into the space after the start, and a write the store
        did not take, are covered by the next tick.
        """
        while True:
            try:
                name, alive = self._events.get_nowait()
            except queue.Empty:
                break
            if alive != (name in self.alive):
                self.log.info("agent %s %s", name, "arrived" if alive else "gone")
            (self.alive.add if alive else self.alive.discard)(name)
        self._update()

    def _update(self) -> None:
        present = {robot for name in self.alive if (robot := robot_of(name))}
        values: Values = {}
        for robot in self.view.graph.subjects(RDF.type, AC.Robot):
            if not isinstance(robot, URIRef):
                continue
            now = self.view.value(robot, AC.presence)
            if local_name(robot) in present:
                wanted = PRESENT
            elif now == PRESENT:
                wanted = GONE
            else:
                continue
            if now != wanted:
                self.log.info("robot %s: %s", local_name(robot), wanted)
                values[robot, AC.presence] = wanted
        if values:
            self.set_values(values)


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the fleet monitor (see `--help`)."""
    return run_agent(FleetMonitor, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
