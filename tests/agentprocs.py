"""Agent processes for process-level tests: start, kill -9, restart, never leave orphans."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

from rdflib import Graph

REPO = Path(__file__).resolve().parents[1]
ONTOLOGY = REPO / "ontology" / "selfconfig.ttl"
HOSPITAL = REPO / "ontology" / "robots" / "hospital.ttl"


def knowledge() -> Graph:
    """Return the ontology and the hospital robot, as `tspace up` loads them."""
    graph = Graph()
    graph.parse(ONTOLOGY)
    graph.parse(HOSPITAL)
    return graph


class AgentProcess:
    """One `python -m agents.NAME` child process with its log file."""

    def __init__(self, module: str, endpoint: str, space: str, log_dir: Path, *args: str) -> None:
        self.argv = [
            sys.executable,
            "-m",
            f"agents.{module}",
            "--connect",
            endpoint,
            "--space",
            space,
            *args,
        ]
        self.log = log_dir / f"{module}-{space}.log"
        self.proc: subprocess.Popen | None = None

    def start(self) -> AgentProcess:
        """Start (or restart) the process."""
        with open(self.log, "ab") as log:
            self.proc = subprocess.Popen(
                self.argv, cwd=REPO, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
            )
        return self

    def alive(self) -> bool:
        """Return True while the process runs."""
        return self.proc is not None and self.proc.poll() is None

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 10) -> int:
        """Send `sig`, wait for the exit and return the exit code (SIGKILL after `timeout`)."""
        assert self.proc is not None
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
            raise

    def logs(self) -> str:
        """Return what the process printed."""
        return self.log.read_text(errors="replace") if self.log.exists() else ""


class Launcher:
    """Starts agent processes for one test and kills whatever is left at the end."""

    def __init__(self, endpoint: str, space: str, log_dir: Path) -> None:
        self.endpoint, self.space, self.log_dir = endpoint, space, log_dir
        self.procs: list[AgentProcess] = []

    def start(self, module: str, *args: str) -> AgentProcess:
        """Start `python -m agents.MODULE` on the test's space."""
        proc = AgentProcess(module, self.endpoint, self.space, self.log_dir, *args).start()
        self.procs.append(proc)
        return proc

    def close(self) -> None:
        """Kill every process still running."""
        for proc in self.procs:
            if proc.alive():
                assert proc.proc is not None
                os.killpg(proc.proc.pid, signal.SIGKILL)
                proc.proc.wait()


def value(ts: object, subject: object, predicate: object) -> object:
    """Return the one object of (subject, predicate) in the space, None if absent."""
    found = sorted(ts.query((subject, predicate, None)).objects())  # type: ignore[attr-defined]
    return found[0] if len(found) == 1 else None


def alive(ts: object, name: str) -> bool:
    """Return True if agent `name` holds its liveliness token in the test's space."""
    key = f"tspace/{ts.space}/@agents/{name}"  # type: ignore[attr-defined]
    replies = ts.session.liveliness().get(key, timeout=2.0)  # type: ignore[attr-defined]
    return any(reply.ok is not None for reply in replies)
