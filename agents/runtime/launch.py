"""Launch files: which agents `tspace up` runs for a space, read from TOML.

A launch file names the space, its robots and its agents; `tspace up` turns it
into one process per agent (per robot for `per_robot` agents). The format is
documented in `docs/operations.md`.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

from space import InputError, check_lifespan


@dataclass(frozen=True)
class AgentSpec:
    """One agent process of a launch file.

    Attributes:
        name: unique process name, shown in the live view and in restart messages.
        module: the Python module run with `python -m`.
        robot: the robot this process serves (`--robot`), or None for fleet agents.
        args: extra command-line options, paths already resolved.
        restart: whether the supervisor restarts the process when it exits.
    """

    name: str
    module: str
    robot: str | None = None
    args: tuple[str, ...] = ()
    restart: bool = True

    def option(self, flag: str) -> str | None:
        """Return the value given to `flag` in `args`, or None."""
        for index, arg in enumerate(self.args):
            if arg == flag and index + 1 < len(self.args):
                return self.args[index + 1]
            if arg.startswith(flag + "="):
                return arg.split("=", 1)[1]
        return None


@dataclass(frozen=True)
class Launch:
    """A parsed launch file.

    Attributes:
        space: the space's name (`--space` of every agent).
        robots: the robots' local names in the `ac:` namespace.
        agents: the processes to run, in start order.
        load: Turtle files written into the space once the store is up.
        grace: seconds between SIGTERM and SIGKILL when stopping.
        backoff: first and longest delay before restarting a crashed agent.
        path: where the file was read from.
    """

    space: str
    robots: tuple[str, ...]
    agents: tuple[AgentSpec, ...]
    load: tuple[Path, ...] = ()
    grace: float = 5.0
    backoff: tuple[float, float] = (0.5, 30.0)
    path: Path | None = None

    def with_args(self, extra: dict[str, list[str]]) -> Launch:
        """Return a copy whose agents get `extra[name]` appended to their args.

        Keys are agent names as written in the launch file, so a scenario can tune,
        say, `hw_monitor` of every robot.
        """
        agents = tuple(
            replace(a, args=a.args + tuple(extra.get(a.name.split("/")[0], ())))
            for a in self.agents
        )
        return replace(self, agents=agents)


def _strings(value: object, what: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str | int | float) for v in value):
        raise InputError(f"{what} must be a list of strings, got {value!r}")
    return tuple(str(v) for v in value)


def _agents(entries: object, robots: tuple[str, ...], base: Path) -> tuple[AgentSpec, ...]:
    if not isinstance(entries, list) or not entries:
        raise InputError("a launch file needs at least one [[agent]] table")
    specs: list[AgentSpec] = []
    for entry in entries:
        if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
            raise InputError(f"every [[agent]] needs a name: {entry!r}")
        known = {"name", "module", "args", "per_robot", "restart", "paths", "lifespan"}
        unknown = set(entry) - known
        if unknown:
            raise InputError(f"agent {entry['name']}: unknown keys {sorted(unknown)}")
        name = entry["name"]
        args = list(_strings(entry.get("args", []), f"agent {name}: args"))
        # Options that name files are resolved against the launch file's folder,
        # so `tspace up deploy/x.toml` works from any directory.
        for flag in _strings(entry.get("paths", []), f"agent {name}: paths"):
            for index, arg in enumerate(args[:-1]):
                if arg == flag:
                    args[index + 1] = str((base / args[index + 1]).resolve())
        if "lifespan" in entry:  # the agent's default lifespan for what it writes
            try:
                life = check_lifespan(entry["lifespan"])
            except InputError as exc:
                raise InputError(f"agent {name}: {exc}") from exc
            if life:
                args += ["--lifespan", f"{life:g}s"]
        module = entry.get("module", f"agents.{name}")
        restart = bool(entry.get("restart", True))
        for_robots: tuple[str | None, ...] = robots if entry.get("per_robot", False) else (None,)
        for robot in for_robots:
            label = f"{name}/{robot}" if robot and len(robots) > 1 else name
            specs.append(AgentSpec(label, module, robot, tuple(args), restart))
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise InputError(f"agent names must be unique: {names}")
    return tuple(specs)


def read_launch(path: str | Path) -> Launch:
    """Read and check a launch file.

    Raises:
        InputError: the file is missing, not TOML, or does not have the expected shape.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"cannot read launch file {path}: {exc.strerror}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: {exc}") from exc
    base = path.parent
    space = data.get("space", "default")
    robots = _strings(data.get("robots", []), "robots")
    if not isinstance(space, str) or not space:
        raise InputError(f"{path}: space must be a non-empty string")
    supervision = data.get("supervisor", {})
    load = tuple((base / p).resolve() for p in _strings(data.get("load", []), "load"))
    missing = [str(p) for p in load if not p.is_file()]
    if missing:
        raise InputError(f"{path}: files to load do not exist: {missing}")
    return Launch(
        space=space,
        robots=robots,
        agents=_agents(data.get("agent"), robots, base),
        load=load,
        grace=float(supervision.get("grace", 5.0)),
        backoff=(
            float(supervision.get("backoff_initial", 0.5)),
            float(supervision.get("backoff_max", 30.0)),
        ),
        path=path,
    )
