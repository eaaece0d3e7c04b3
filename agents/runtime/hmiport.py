"""Choose the HMI's port before `tspace up` starts it, so the URL it prints is the real one.

An HMI agent whose port is taken exits and is restarted in a loop; checking
first turns that into one line at start (a port someone named) or another
port (the default, which anything may hold).
"""

from __future__ import annotations

from collections.abc import Callable

from agents.runtime.launch import AgentSpec
from space import InputError, any_free_port, probe_port

DEFAULT_PORT = 8080
DEFAULT_HOST = "127.0.0.1"


def port_free(host: str, port: int) -> bool:
    """Return True if a server could listen on `host:port` now (see `space.probe_port`)."""
    try:
        probe_port(host, port)
    except OSError:
        return False
    return True


def choose_port(
    agent: AgentSpec,
    named: int | None,
    report: Callable[[str], None],
    host: str | None = None,
) -> int:
    """Return the port the HMI agent will serve on.

    Args:
        agent: the HMI agent of the launch file (its `--http-port`, `--http-host`).
        named: the port given to `tspace up --hmi-port`, which wins over the file.
        report: told when the default port is taken and another one is used.
        host: the address given to `tspace up --hmi-listen`, which wins over the file.

    Raises:
        InputError: the port `--hmi-port` or the launch file names is taken, or not a number.
    """
    host = host or agent.option("--http-host") or DEFAULT_HOST
    source = "--hmi-port"
    if named is None and agent.option("--http-port") is not None:
        source = f"--http-port of agent {agent.name} in the launch file"
        try:
            named = int(agent.option("--http-port") or "")
        except ValueError as exc:
            raise InputError(f"{source} is not a port: {agent.option('--http-port')!r}") from exc
    if named is not None:
        if not port_free(host, named):
            raise InputError(f"HMI port {named} ({source}) is already in use on {host}")
        return named
    if port_free(host, DEFAULT_PORT):
        return DEFAULT_PORT
    port = any_free_port(host)
    report(f"HMI port {DEFAULT_PORT} is already in use on {host}; using {port}")
    return port
