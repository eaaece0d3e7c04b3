"""Shared bench plumbing: a `tspace serve` child on a free port, and statistics."""

from __future__ import annotations

import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from space import SpaceError, TripleSpace, load_identity


def _stop_on_sigterm(signum: int, _frame: object) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second one must not cut the cleanup short
    raise SystemExit(128 + signum)


# A bench stopped by `kill` (SIGTERM) unwinds as on Ctrl-C, so that the `finally` blocks
# stop the store and agent processes it started: by default they outlived it.
if signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
    signal.signal(signal.SIGTERM, _stop_on_sigterm)


def free_port() -> int:
    """Return a TCP port free on 127.0.0.1 now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def code_env(code: Path | None) -> dict[str, str]:
    """Return the environment that runs `python -m space...` from the source tree `code`."""
    env = dict(os.environ)
    if code is not None:
        env["PYTHONPATH"] = str(code)
    return env


@contextmanager
def serve(secure: Path | None = None) -> Iterator[str]:
    """Run `tspace serve` on a fresh data dir; yield its endpoint; stop it after.

    With `secure` (a `tspace certs` directory), mutual TLS and the shipped policy.
    """
    with serve_process(None, secure=secure) as (endpoint, _pid):
        yield endpoint


@contextmanager
def serve_process(
    code: Path | None = None, *extra: str, secure: Path | None = None
) -> Iterator[tuple[str, int]]:
    """Run `tspace serve` on a fresh data dir; yield its endpoint and pid; stop it after.

    `code`: a source tree to run the server from (an older commit's worktree),
    instead of the installed one; `extra`: more `serve` options; `secure` (a
    `tspace certs` directory): mutual TLS and the shipped policy.
    """
    endpoint = f"{'tls' if secure else 'tcp'}/127.0.0.1:{free_port()}"
    identity = load_identity(secure, "operator") if secure else None
    extra = (*extra, "--secure", str(secure)) if secure else extra
    with tempfile.TemporaryDirectory() as data:
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "space.cli",
                "serve",
                "--listen",
                endpoint,
                "--data",
                data,
                *extra,
            ],
            stderr=subprocess.DEVNULL,
            env=code_env(code),
            cwd=str(code) if code is not None else None,
        )
        try:
            deadline = time.monotonic() + 20
            while True:
                try:
                    with TripleSpace.open(endpoint, space="ping", identity=identity) as ts:
                        ts.snapshot(timeout=1)
                    break
                except SpaceError:
                    if time.monotonic() > deadline:
                        raise
                    time.sleep(0.05)
            yield endpoint, proc.pid
        finally:
            proc.terminate()
            reap([proc])  # one still busy (an old store finishing a query) is killed


def reap(procs: Sequence[subprocess.Popen], timeout: float = 10.0) -> None:
    """Wait for processes told to stop; kill those still running after `timeout` s each."""
    for proc in procs:
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def cpu_seconds(pids: Sequence[int]) -> float:
    """Return the CPU time (user + system) processes `pids` have used so far."""
    total = 0
    for pid in pids:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += int(fields[11]) + int(fields[12])  # utime, stime
    return total / os.sysconf("SC_CLK_TCK")


def percentile(values: Sequence[float], q: float) -> float:
    """Return the q-th percentile (0..100) by nearest rank."""
    ordered = sorted(values)
    index = min(len(ordered) - 1, max(0, round(q / 100 * (len(ordered) - 1))))
    return ordered[index]


def median(values: Sequence[float]) -> float:
    """Return the median."""
    return statistics.median(values)
