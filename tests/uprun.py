"""A `tspace up` child process for tests: its output collected, its process tree tracked."""

from __future__ import annotations

import os
import signal
import subprocess
import threading
from pathlib import Path

from conftest import free_port, tspace_cmd, wait_for


def alive(pid: int) -> bool:
    """Return True if `pid` is a live (not zombie) process."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def children(pid: int) -> list[int]:
    """Return the direct children of `pid`."""
    found: list[int] = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            found += [int(c) for c in (task / "children").read_text().split()]
        except FileNotFoundError:
            continue
    return found


def cmdline(pid: int) -> str:
    """Return the command line of `pid` ("" if it is gone)."""
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except FileNotFoundError:
        return ""


class Up:
    """Run `tspace up` on free ports and a fresh data dir, collecting stdout and stderr.

    `launch` None runs the default launch file; `name_hmi_port` False lets `tspace up`
    choose the HMI's port (`hmi_port` is then None); `cwd` is where it runs; `scheme`
    is the router's (`tls` with `--secure`).
    Use as a context manager: on exit the whole process tree is killed, whatever happened.
    """

    def __init__(
        self,
        tmp: Path,
        launch: Path | None,
        *extra: str,
        name_hmi_port: bool = True,
        cwd: Path | None = None,
        scheme: str = "tcp",
    ) -> None:
        self.port = free_port()
        self.hmi_port = free_port() if name_hmi_port else None
        self.data = tmp / "data"
        self.cwd = cwd
        self.argv = tspace_cmd(
            "up",
            *([str(launch)] if launch is not None else []),
            "--listen",
            f"{scheme}/127.0.0.1:{self.port}",
            "--data",
            str(self.data),
            *(["--hmi-port", str(self.hmi_port)] if self.hmi_port is not None else []),
            *extra,
        )
        self.out: list[str] = []
        self.err: list[str] = []
        self.proc: subprocess.Popen[str] | None = None
        self.seen: set[int] = set()

    def __enter__(self) -> Up:
        self.proc = subprocess.Popen(
            self.argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=self.cwd
        )
        for stream, lines in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=self._collect, args=(stream, lines), daemon=True).start()
        return self

    def __exit__(self, *exc: object) -> None:
        assert self.proc is not None
        self.track()
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        for pid in self.seen:
            if alive(pid):
                os.killpg(pid, signal.SIGKILL)

    @staticmethod
    def _collect(stream: object, lines: list[str]) -> None:
        for line in stream:  # type: ignore[attr-defined]
            lines.append(line.rstrip("\n"))

    def track(self) -> list[int]:
        """Remember (for cleanup) and return the pids of the supervised processes now."""
        assert self.proc is not None
        pids = children(self.proc.pid)
        self.seen.update(pids)
        return pids

    def pid_of(self, module: str) -> int | None:
        """Return the pid of the running child whose command runs `module`."""
        return next((p for p in self.track() if f"-m {module} " in cmdline(p) + " "), None)

    def stdout_has(self, text: str) -> bool:
        """Return True if a line of stdout contains `text`."""
        return any(text in line for line in list(self.out))

    def stderr_has(self, text: str) -> bool:
        """Return True if a line of stderr contains `text`."""
        return any(text in line for line in list(self.err))

    def logs(self) -> str:
        """Return the output and every child's log, to explain a failure."""
        parts = ["--- stdout", *self.out, "--- stderr", *self.err]
        for log in sorted((self.data / "logs").glob("*.log")):
            parts += [f"--- {log.name}", log.read_text(errors="replace")[-3000:]]
        return "\n".join(parts)

    def wait_started(self, timeout: float = 30.0) -> None:
        """Wait until the store answers and the agents have been started."""
        wait_for(
            lambda: self.stderr_has(" agents; logs in ") or self.proc.poll() is not None,  # type: ignore[union-attr]
            timeout,
            "tspace up to start its agents",
        )
        assert self.proc is not None and self.proc.poll() is None, self.logs()

    def wait_connected(self, *agents: str, timeout: float = 30.0) -> None:
        """Wait until each named agent's log says it connected to the space."""
        for agent in agents:
            log = self.data / "logs" / f"{agent}.log"
            wait_for(
                lambda log=log: log.exists() and "connected to space" in log.read_text(),
                timeout,
                f"{agent} to connect",
                self.logs,
            )
