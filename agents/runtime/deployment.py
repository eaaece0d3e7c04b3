"""One run of `tspace up`: the store, the agents, the live view and maybe a scenario.

Everything is driven from the main thread: it starts and restarts the
processes (the supervisor's PR_SET_PDEATHSIG is tied to this thread), runs the
scenario's actions and draws the view. The space is watched through a
`SpaceMirror`, whose updates arrive on the client's dispatcher thread.
"""

from __future__ import annotations

import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from types import FrameType

from agents.runtime.hmiport import choose_port
from agents.runtime.launch import AgentSpec, Launch
from agents.runtime.liveview import Frame, LiveView, robot_line
from agents.runtime.robotview import BadValues, read_firings, read_robots
from agents.runtime.scenario import Scenario, ScenarioRun
from agents.runtime.supervisor import ProcessSpec, Supervisor
from space import (
    ClusterWatch,
    SpaceError,
    SpaceMirror,
    TripleSpace,
    check_can_listen,
    load_identity,
    read_turtle,
)

STORE_STARTUP = 30.0
TICK = 0.1
# Firings a frame reads: in log mode each one is printed once, so a burst of answers
# between two frames must not push one out unprinted.
FIRINGS_SHOWN = 100


@dataclass(frozen=True)
class Options:
    """What `tspace up` was asked to run (see `agents.runtime.up`)."""

    launch: Launch
    listen: list[str]
    data: Path
    hmi_port: int | None = None
    hmi_listen: str | None = None  # the HMI's address (the launch file's, else 127.0.0.1)
    scenario: Scenario | None = None
    once: bool = False
    step_timeout: float = 90.0
    fresh: bool = False
    secure: Path | None = None  # certificates: mutual TLS only, every process its identity
    policy: Path | None = None


def client_endpoint(listen: str) -> str:
    """Return the endpoint a local process connects to for a router listening on `listen`."""
    for wildcard in ("0.0.0.0", "[::]"):
        listen = listen.replace(f"/{wildcard}:", "/127.0.0.1:")
    return listen


def identity_of_agent(agent: AgentSpec) -> str:
    """Return the identity `tspace certs init --fleet` made for an agent: KIND.ROBOT or KIND."""
    kind = agent.name.split("/")[0]
    return f"{kind}.{agent.robot}" if agent.robot else kind


class Deployment:
    """Run a launch file until stopped.

    Args:
        options: what to run.
        view: where to show it.
    """

    def __init__(self, options: Options, view: LiveView) -> None:
        launch = options.launch
        if options.scenario is not None:
            launch = launch.with_args(options.scenario.agent_args)
        self.options = options
        self.launch = launch
        self.view = view
        self.connect = client_endpoint(options.listen[0])
        # Set by the signal handler, read by the loops every TICK: a plain flag, since a
        # handler that takes a lock (Event.set) deadlocks when a second Ctrl-C lands
        # while the first one holds it, or while the loop's own wait holds it.
        self.stop_requested = False
        self.supervisor = Supervisor(
            log_dir=options.data / "logs",
            on_event=view.event,
            grace=launch.grace,
            backoff=launch.backoff,
        )
        self.mirror = SpaceMirror()
        self.bad_values = BadValues(view.event)
        self._said: dict[str, str] = {}  # firings' sentences by changeset id
        self._view_failure = ""
        self.scenario: ScenarioRun | None = None
        self.cluster: ClusterWatch | None = None
        self.robot = launch.robots[0] if launch.robots else "robot1"
        self.hmi_port: int | None = None
        self.operator = None
        if options.secure is not None:  # every certificate is there, or say which is not, now
            self.operator = load_identity(options.secure, "operator")
            for agent in launch.agents:
                load_identity(options.secure, identity_of_agent(agent))

    def hmi_agent(self) -> AgentSpec | None:
        """Return the launch file's HMI agent, if it has one."""
        return next((a for a in self.launch.agents if a.module == "agents.hmi"), None)

    def agent_argv(self, agent: AgentSpec) -> tuple[str, ...]:
        """Return the command line of one agent process."""
        argv = [sys.executable, "-m", agent.module, "--connect", self.connect]
        argv += ["--space", self.launch.space]
        if self.options.secure is not None:
            # Its identity is its name too: the routers let it declare a liveliness token
            # under that name only.
            identity = identity_of_agent(agent)
            argv += ["--secure", str(self.options.secure), "--identity", identity]
            argv += ["--name", identity]
        if agent.robot:
            argv += ["--robot", agent.robot]
        args = list(agent.args)
        if self.hmi_port is not None and agent.module == "agents.hmi":
            args = _set_option(args, "--http-port", str(self.hmi_port))
            if self.options.hmi_listen:
                args = _set_option(args, "--http-host", self.options.hmi_listen)
        return (*argv, *args)

    def hmi_url(self) -> str | None:
        """Return the URL of the HMI agent's page, once `run` chose its port."""
        if self.hmi_port is None:
            return None
        host = self.options.hmi_listen or "127.0.0.1"
        host = "127.0.0.1" if host in ("0.0.0.0", "::") else host
        return f"http://{f'[{host}]' if ':' in host else host}:{self.hmi_port}/"

    def run(self) -> int:
        """Start everything, show it until stopped, stop everything; return the exit code.

        Must be called from the main thread (it installs SIGINT and SIGTERM handlers).

        Raises:
            ConfigError: with `secure`, a process's certificate is missing (checked at
                construction, before anything starts).
            ConfigError, ListenFailed: the store's router could not listen on `listen`
                (checked before anything starts, so the user reads why at once).
            InputError: the HMI's port, named by `--hmi-port` or the launch file, is taken.
        """
        check_can_listen(self.options.listen)
        hmi = self.hmi_agent()
        if hmi is not None:
            self.hmi_port = choose_port(
                hmi, self.options.hmi_port, self.view.event, self.options.hmi_listen
            )
        previous = {
            sig: signal.signal(sig, self._on_signal) for sig in (signal.SIGINT, signal.SIGTERM)
        }
        ts: TripleSpace | None = None
        try:
            serve = (sys.executable, "-m", "space.cli", "serve", "--data", str(self.options.data))
            for endpoint in self.options.listen:
                serve += ("--listen", endpoint)
            if self.options.secure is not None:
                serve += ("--secure", str(self.options.secure))
            if self.options.policy is not None:
                serve += ("--policy", str(self.options.policy))
            self.supervisor.start(ProcessSpec("serve", serve, tier=0))
            ts = self._wait_for_store()
            if ts is None:
                return 1
            scenario = self.options.scenario
            # A scenario is a story from its own start: never from where a last run stopped.
            self._load(ts, fresh=self.options.fresh or scenario is not None)
            if scenario is not None and scenario.prepare is not None:
                scenario.prepare(ts, self.robot)
            for agent in self.launch.agents:
                self.supervisor.start(
                    ProcessSpec(agent.name, self.agent_argv(agent), restart=agent.restart)
                )
            self.view.event(
                f"started {len(self.launch.agents)} agents; logs in {self.options.data / 'logs'}"
            )
            url = self.hmi_url()
            if url:
                self.view.event(f"HMI at {url}")
            return self._loop(ts)
        finally:
            self.mirror.detach()
            if self.cluster is not None:
                self.cluster.close()
                self.cluster = None
            if ts is not None:
                ts.close()
            self.supervisor.stop()
            self.view.close()
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        self.stop_requested = True

    def _wait_for_store(self) -> TripleSpace | None:
        """Return a handle once the store answers; None if stopped or it never does."""
        deadline = time.monotonic() + STORE_STARTUP
        ts: TripleSpace | None = None
        while not self.stop_requested:
            self.supervisor.poll()
            try:
                if ts is None:
                    ts = TripleSpace.open(
                        self.connect,
                        space=self.launch.space,
                        agent="tspace-up",
                        identity=self.operator,
                    )
                ts.snapshot((None, None, None), timeout=1.0)
                return ts
            except SpaceError as exc:
                if time.monotonic() > deadline:
                    log = self.supervisor.log_path("serve")
                    self.view.event(f"no store after {STORE_STARTUP:.0f} s ({exc}); see {log}")
                    break
            time.sleep(TICK)
        if ts is not None:
            ts.close()
        return None

    def _load(self, ts: TripleSpace, *, fresh: bool) -> None:
        """Write the launch file's Turtle files into a space that is empty, or emptied if `fresh`.

        Without `fresh` a space that holds anything is left as it is: the robots
        resume where they were.
        """
        asserted, inferred, _ = ts.graphs((None, None, None), timeout=10.0)
        held = len(asserted) + len(inferred)
        if held and fresh:
            # One changeset: a subscriber sees the old state go at once, never half of it.
            ts.apply(removed=asserted, inferred_removed=inferred, timeout=60.0)
            self.view.event(f"space {self.launch.space}: started afresh ({held} triples removed)")
        elif held:
            self.view.event(
                f"space {self.launch.space} holds {held} triples; resuming from them "
                "(--fresh starts over)"
            )
            return
        if not self.launch.load:
            return
        for path in self.launch.load:
            graph = read_turtle(str(path))
            ts.write(graph, timeout=10.0)
            self.view.event(f"loaded {path.name} ({len(graph)} triples)")

    def _loop(self, ts: TripleSpace) -> int:
        options = self.options
        if options.scenario is not None:
            self.scenario = ScenarioRun(
                options.scenario, self.robot, self.view.event, step_timeout=options.step_timeout
            )
        if self.scenario is not None or self.view.logs_every_change:
            self.mirror.watch(self._on_change)
        self.mirror.attach(ts)
        # Replicas on etcd say whether they reach a quorum; an embedded store says nothing.
        self.cluster = ClusterWatch(ts.session)
        told = ""
        shown, shown_at = -1, 0.0
        while not self.stop_requested:
            self.supervisor.poll()
            if self.cluster.line() != told:
                told = self.cluster.line()
                self.view.event(told or "store replicas: none heard from")
            if self.scenario is not None:
                status = self._tick_scenario(ts, self.scenario)
                if status is not None:
                    self._show(final=True)
                    return status
            # Reading the robots copies the graph: only when it changed, or to
            # refresh process states once a second.
            if self.mirror.version != shown or time.monotonic() - shown_at > 1.0:
                shown, shown_at = self.mirror.version, time.monotonic()
                self._show()
            time.sleep(TICK)
        if options.once:
            print("tspace up: stopped before the scenario completed", file=sys.stderr)
            return 1
        return 0

    def _on_change(self) -> None:
        """Read the robots after each changeset, so the scenario and the log see every state."""
        robots = read_robots(self.mirror.copy(), self.bad_values)
        self.view.robots(robots)
        if self.scenario is not None:
            self.scenario.observe(robots)

    def _tick_scenario(self, ts: TripleSpace, run: ScenarioRun) -> int | None:
        """Advance the scenario; return an exit code when a `--once` run is over."""
        if run.finishing:
            # Show the state the last step happened on before the finishing action
            # (the robot told to idle) changes it: the view's story ends with that step.
            self._show()
        try:
            run.tick(ts, self.mirror)
        except SpaceError as exc:
            self.view.event(f"scenario: could not act on the space ({exc}); retrying")
        if not self.options.once:
            return None
        if run.finished:
            try:
                run.tick(ts, self.mirror)  # its finishing action, if not run yet
            except SpaceError as exc:
                self.view.event(f"scenario: could not finish ({exc})")
            print(f"scenario {run.scenario.name}: completed", flush=True)
            return 0
        if run.failure is not None:
            robots = read_robots(self.mirror.copy(), self.bad_values)
            state = "; ".join(robot_line(r) for r in robots) or "no robot in the space"
            print(
                f"tspace up: scenario {run.scenario.name} failed: {run.failure} (now: {state})",
                file=sys.stderr,
            )
            return 1
        return None

    def _show(self, final: bool = False) -> None:
        """Draw the view; a drawing that fails is reported once, and the processes run on."""
        try:
            self.view.show(self._frame(), final=final)
        except Exception as exc:  # the supervisor's loop must outlive any picture of the space
            if repr(exc) != self._view_failure:
                self._view_failure = repr(exc)
                self.view.event(f"cannot show the space: {exc!r}")

    def _frame(self) -> Frame:
        listen = ", ".join(self.options.listen)
        header = f"tspace up: space {self.launch.space} on {listen}, data {self.options.data}"
        url = self.hmi_url()
        if url:
            header += f", HMI {url}"
        if self.cluster is not None and self.cluster.line():
            header += f"\n{self.cluster.line()}"
        graph = self.mirror.copy()
        # In log mode the robots are logged per change (`_on_change`), not from a frame.
        logged = self.view.logs_every_change
        return Frame(
            header=header,
            robots=[] if logged else read_robots(graph, self.bad_values),
            firings=read_firings(self.mirror.recent(), FIRINGS_SHOWN, graph, self._said),
            processes=self.supervisor.status(),
            footer=self.scenario.progress if self.scenario else "Ctrl-C stops everything.",
        )


def _set_option(args: list[str], flag: str, value: str) -> list[str]:
    """Return `args` with `flag`'s value replaced (or the option appended)."""
    out = list(args)
    for index, arg in enumerate(out[:-1]):
        if arg == flag:
            out[index + 1] = value
            return out
    return [*out, flag, value]
