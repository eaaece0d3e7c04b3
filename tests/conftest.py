"""Fixtures: a real Zenoh router with the space store (`tspace serve`) on a free loopback port."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from agentprocs import Launcher

from space import TripleSpace
from space.errors import SpaceError

REPO = Path(__file__).resolve().parents[1]
PYTHON = sys.executable


def free_port() -> int:
    """Return a TCP port free on 127.0.0.1 now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(
    condition: Callable[[], object],
    timeout: float = 10.0,
    what: str = "condition",
    explain: Callable[[], str] | None = None,
) -> object:
    """Poll `condition` until it returns a truthy value; fail the test after `timeout`.

    `explain`, if given, is called on failure and its text (logs, say) added to the message.
    """
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            detail = f"\n{explain()}" if explain is not None else ""
            pytest.fail(f"timed out after {timeout} s waiting for {what}{detail}")
        time.sleep(0.02)


def store_answers(endpoint: str) -> bool:
    """Return True when a store answers through the router at `endpoint` within a second."""
    try:
        with TripleSpace.open(endpoint, space="ping") as ts:
            ts.snapshot(timeout=1.0)
        return True
    except SpaceError:
        return False


def tspace_cmd(*args: str) -> list[str]:
    """Return the argv that runs `tspace ARGS` with this interpreter."""
    return [PYTHON, "-m", "space.cli", *args]


class Server:
    """A `tspace serve` child process: router + store, restartable on the same port and data."""

    def __init__(self, data_dir: Path, *extra: str) -> None:
        self.extra = extra
        self.port = free_port()
        self.endpoint = f"tcp/127.0.0.1:{self.port}"
        self.data_dir = data_dir
        self.proc: subprocess.Popen | None = None
        self.log = data_dir.parent / f"serve-{self.port}.log"

    def start(self, *, wait: bool = True) -> None:
        """Start the process and, with `wait`, wait until a store answers through it."""
        with open(self.log, "ab") as log:
            self.proc = subprocess.Popen(
                tspace_cmd(
                    "serve", "--listen", self.endpoint, "--data", str(self.data_dir), *self.extra
                ),
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        if wait:
            wait_for(self._answers, 20, f"tspace serve on {self.endpoint}")

    def reachable(self) -> bool:
        """Return True when a store answers through this process's router."""
        return self._answers()

    def _answers(self) -> bool:
        assert self.proc is not None
        if self.proc.poll() is not None:
            pytest.fail(f"tspace serve exited with {self.proc.returncode}: {self.log.read_text()}")
        return store_answers(self.endpoint)

    def stop(self, sig: int = signal.SIGTERM) -> int:
        """Stop the process with `sig` and return its exit code."""
        assert self.proc is not None
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            return self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            return self.proc.wait()

    def logs(self) -> str:
        """Return what the process printed."""
        return self.log.read_text(errors="replace")


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """A router + store for the whole test module."""
    srv = Server(tmp_path_factory.mktemp("store") / "data")
    srv.start()
    try:
        yield srv
    finally:
        srv.stop()


@pytest.fixture
def space_name() -> str:
    """A space name of its own for each test, so tests sharing a server don't meet."""
    return f"t{uuid.uuid4().hex[:10]}"


@pytest.fixture
def ts(server: Server, space_name: str) -> Iterator[TripleSpace]:
    """A client on the test's own space."""
    with TripleSpace.open(
        server.endpoint, space=space_name, agent="test", prefixes={"ac": AC_NS}
    ) as handle:
        yield handle


AC_NS = "https://w3id.org/tspace/selfconfig#"


@pytest.fixture
def run_tspace(server: Server, space_name: str) -> Callable[..., subprocess.CompletedProcess]:
    """Run a `tspace` sub-command against the test's server and space."""

    def run(
        *args: str, stdin: str | None = None, timeout: float = 30
    ) -> subprocess.CompletedProcess:
        cmd = tspace_cmd(*args, "--connect", server.endpoint, "--space", space_name)
        return subprocess.run(cmd, input=stdin, capture_output=True, text=True, timeout=timeout)

    return run


@pytest.fixture
def launch(server: Server, space_name: str, tmp_path: Path) -> Iterator[Launcher]:
    """Start agent processes on the module's router; every one is stopped at the end."""
    launcher = Launcher(server.endpoint, space_name, tmp_path)
    try:
        yield launcher
    finally:
        launcher.close()


@pytest.fixture
def etcd_cluster(tmp_path: Path) -> Iterator[object]:
    """Three real etcd members on loopback ports, writable when the test starts; killed after."""
    import asyncio

    from space.store.etcd_member import LocalCluster, etcd_missing

    if etcd_missing():
        pytest.skip(etcd_missing())
    with LocalCluster(tmp_path / "etcd") as cluster:
        asyncio.run(_until_writable(cluster.endpoints))
        yield cluster


@pytest.fixture
def replicas(etcd_cluster, tmp_path: Path) -> Iterator[list[Server]]:
    """Three replicas of one etcd cluster, each behind its own router."""
    members = ",".join(etcd_cluster.endpoints)
    servers = [Server(tmp_path / f"r{i}" / "data", "--cluster", members) for i in range(3)]
    for s in servers:
        s.data_dir.parent.mkdir(parents=True)
        s.start(wait=False)
    try:
        for s in servers:
            wait_for(s.reachable, 30, f"replica on {s.endpoint}", s.logs)
        yield servers
    finally:
        for s in servers:
            s.stop()


async def _until_writable(endpoints: list[str], timeout: float = 20.0) -> None:
    from aetcd import rpc

    from space.errors import NoQuorum
    from space.store.etcd_client import EtcdClient

    client = EtcdClient(endpoints)
    await client.open()
    deadline = time.monotonic() + timeout
    try:
        while True:
            try:
                await client.range(rpc.RangeRequest(key=b"probe"))
                return
            except NoQuorum:
                if time.monotonic() > deadline:
                    raise
    finally:
        await client.close()


def serve_refusal(data: Path) -> str:
    """Run `tspace serve` on a data directory it must refuse; return its one line saying why."""
    done = subprocess.run(
        tspace_cmd("serve", "--listen", f"tcp/127.0.0.1:{free_port()}", "--data", str(data)),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 1, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.startswith("tspace serve:")]
    assert len(lines) == 1, done.stderr
    return lines[0]


def newer_format_dir(data: Path) -> object:
    """Make `data` a directory whose store a newer tspace wrote (format 99); return its
    marker quad."""
    import pyoxigraph as ox

    data.mkdir()
    store = ox.Store(str(data / "oxigraph"))
    marker = ox.Quad(
        ox.NamedNode("urn:tspace:store"),
        ox.NamedNode("urn:tspace:format"),
        ox.Literal("99"),
        ox.NamedNode("urn:tspace:meta"),
    )
    store.add(marker)
    store.flush()
    del store
    return marker
