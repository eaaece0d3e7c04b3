"""Run a set of child processes, restart the ones that crash, stop them all.

Each child gets its own process group (so a stop reaches whatever it spawned)
and dies with the supervisor even when the supervisor is killed with SIGKILL:
a tiny trampoline sets Linux's PR_SET_PDEATHSIG before exec-ing the real
command. The trampoline avoids `preexec_fn`, which is unsafe once Zenoh's
threads are running. The kernel ties PDEATHSIG to the thread that forked, so
every `start` and `poll` must be called from one thread that lives as long as
the supervisor (the main thread of `tspace up`).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

# Runs in the child before exec: die with the parent, and give up if the
# parent already died between fork and prctl.
_TRAMPOLINE = """\
import ctypes, os, signal, sys
ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
if os.getppid() != int(sys.argv[1]):
    sys.exit(1)
os.execvp(sys.argv[2], sys.argv[2:])
"""

# A child that ran this long before crashing is restarted without delay growth.
STABLE_AFTER = 10.0


@dataclass(frozen=True)
class ProcessSpec:
    """What to run.

    Attributes:
        name: unique name, used in messages and for the log file.
        argv: the command.
        restart: restart when it exits with a non-zero code or a signal.
        tier: stop order; higher tiers are stopped first (agents before the store).
    """

    name: str
    argv: tuple[str, ...]
    restart: bool = True
    tier: int = 1


@dataclass
class _Child:
    spec: ProcessSpec
    proc: subprocess.Popen[bytes] | None = None
    log: IO[bytes] | None = None
    started: float = 0.0
    restarts: int = 0
    failures: int = 0
    restart_at: float | None = None
    exit_status: str | None = None


@dataclass(frozen=True)
class ProcessStatus:
    """A child as the live view shows it."""

    name: str
    pid: int | None
    running: bool
    restarts: int
    exit_status: str | None


@dataclass
class Supervisor:
    """Start, watch, restart and stop child processes.

    Args:
        log_dir: each child's stdout and stderr are appended to `<log_dir>/<name>.log`.
        on_event: called with one line for each start, exit and restart
            (from the thread that calls `start`/`poll`/`stop`).
        grace: seconds between SIGTERM and SIGKILL in `stop`.
        backoff: the first and the longest delay before a restart; the delay
            doubles with each crash in a row.
        env: environment of the children (default: this process's).
    """

    log_dir: Path
    on_event: Callable[[str], None]
    grace: float = 5.0
    backoff: tuple[float, float] = (0.5, 30.0)
    env: dict[str, str] | None = None
    _children: dict[str, _Child] = field(default_factory=dict)

    def start(self, spec: ProcessSpec) -> int:
        """Start `spec` and return its pid.

        Raises:
            ValueError: a child of that name exists already.
            OSError: the command could not be started.
        """
        if spec.name in self._children:
            raise ValueError(f"a process named {spec.name!r} is already supervised")
        child = _Child(spec)
        self._children[spec.name] = child
        self._spawn(child)
        assert child.proc is not None
        return child.proc.pid

    def _spawn(self, child: _Child) -> None:
        self.log_dir.mkdir(parents=True, exist_ok=True)
        if child.log is None:
            path = self.log_dir / (child.spec.name.replace("/", "-") + ".log")
            child.log = path.open("ab")
        argv = [sys.executable, "-I", "-S", "-c", _TRAMPOLINE, str(os.getpid()), *child.spec.argv]
        child.proc = subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=child.log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            env=self.env,
        )
        child.started = time.monotonic()
        child.restart_at = None
        child.exit_status = None

    def log_path(self, name: str) -> Path:
        """Return where the output of child `name` goes."""
        return self.log_dir / (name.replace("/", "-") + ".log")

    def poll(self) -> None:
        """Notice exited children and restart those that are due; never blocks."""
        now = time.monotonic()
        for child in self._children.values():
            if child.proc is not None and child.proc.poll() is not None:
                self._exited(child, now)
            if child.restart_at is not None and now >= child.restart_at:
                child.restarts += 1
                self._spawn(child)
                assert child.proc is not None
                pid, count = child.proc.pid, child.restarts
                self.on_event(f"{child.spec.name}: restarted (pid {pid}, restart #{count})")

    def _exited(self, child: _Child, now: float) -> None:
        assert child.proc is not None
        code = child.proc.returncode
        status = f"killed by {signal.Signals(-code).name}" if code < 0 else f"exit code {code}"
        child.exit_status = status
        # The group may outlive its leader: take what the child left behind with it.
        _kill_group(child.proc.pid, signal.SIGKILL)
        child.proc = None
        if not child.spec.restart or code == 0:
            self.on_event(f"{child.spec.name}: stopped ({status})")
            return
        child.failures = 1 if now - child.started >= STABLE_AFTER else child.failures + 1
        first, longest = self.backoff
        delay = min(first * 2 ** (child.failures - 1), longest)
        child.restart_at = now + delay
        self.on_event(f"{child.spec.name}: crashed ({status}); restarting in {delay:.1f} s")

    def status(self) -> list[ProcessStatus]:
        """Return every child's state, in start order."""
        return [
            ProcessStatus(
                c.spec.name,
                c.proc.pid if c.proc else None,
                c.proc is not None,
                c.restarts,
                c.exit_status,
            )
            for c in self._children.values()
        ]

    def pid(self, name: str) -> int | None:
        """Return the pid of the running child `name`, or None."""
        child = self._children.get(name)
        return child.proc.pid if child and child.proc else None

    def stop(self) -> None:
        """Stop every child, highest tier first; blocks up to `grace` per tier.

        Each tier gets SIGTERM, then SIGKILL for whatever is left after `grace`
        seconds, so nothing survives this call.
        """
        for child in self._children.values():
            child.restart_at = None
        for tier in sorted({c.spec.tier for c in self._children.values()}, reverse=True):
            members = [c for c in self._children.values() if c.spec.tier == tier]
            self._stop_tier(members)
        for child in self._children.values():
            if child.log is not None:
                child.log.close()
                child.log = None

    def _stop_tier(self, members: Sequence[_Child]) -> None:
        running = [c for c in members if c.proc is not None]
        for child in running:
            assert child.proc is not None
            _kill_group(child.proc.pid, signal.SIGTERM)
        deadline = time.monotonic() + self.grace
        for child in running:
            assert child.proc is not None
            try:
                child.proc.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                self.on_event(f"{child.spec.name}: did not stop in {self.grace:.0f} s, killing")
            _kill_group(child.proc.pid, signal.SIGKILL)
            child.proc.wait()
            child.exit_status = "stopped"
            child.proc = None


def _kill_group(pgid: int, sig: signal.Signals) -> None:
    """Send `sig` to a process group; a group that is already gone is fine."""
    try:
        os.killpg(pgid, sig)
    except ProcessLookupError:
        pass
