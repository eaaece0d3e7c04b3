"""Several hosts on one machine: Linux network namespaces joined by veth pairs to a hub bridge.

Multi-host behaviour (routers meshed across hosts, a link cut, a host that
vanishes) needs separate network stacks, not ports on one loopback. Each host
is a namespace with `lo` and an `eth0` whose peer sits on a bridge in a hub
namespace (a star: every host reaches every other), so cutting a host's link
on the hub side is pulling its cable. Every name carries a per-run token, so
parallel runs never meet, and addresses live only inside these namespaces.
`Network.close()` kills every process and deletes every namespace, also when
a test fails.

The test process stays in the root namespace and reaches each host's router
through a Unix socket (paths cross namespaces, TCP does not): that is the
host's `control` endpoint, unaffected by link cuts.

Usage (needs root; `require_netns()` skips with the reason otherwise, or fails
when `TSPACE_REQUIRE_NETNS=1`, as `.ci/run` sets it)::

    with Network(["a", "b"], tmp_path) as net:
        net["a"].serve()                       # router + store
        net["b"].serve(store=False, connect=[net["a"]])
        net["b"].agent("hw_monitor", space="s", robot="robot1")
        with TripleSpace.open(net["b"].control, space="s") as ts: ...
        with net["b"].outage(5.0): ...         # link down, then up again
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType

from space import SpaceError, TripleSpace

REPO = Path(__file__).resolve().parents[1]
SUBNET = "10.47.0"  # only ever configured inside the namespaces made here
PORT = 7447
ROUTER_CONFIG = REPO / "deploy" / "multihost" / "router.json5"
REQUIRE = "TSPACE_REQUIRE_NETNS"  # "1": a test that cannot make namespaces fails, not skips


def netns_unavailable() -> str | None:
    """Return why network namespaces cannot be made here, or None if they can."""
    if not sys.platform.startswith("linux"):
        return "network namespaces need Linux"
    if os.geteuid() != 0:
        return "network namespaces need root (run as root, as CI does)"
    if shutil.which("ip") is None:
        return "the `ip` command (iproute2) is not installed"
    probe = f"tsprobe{uuid.uuid4().hex[:8]}"
    made = subprocess.run(["ip", "netns", "add", probe], capture_output=True, text=True)
    if made.returncode != 0:
        return f"`ip netns add` is not allowed here: {made.stderr.strip()}"
    subprocess.run(["ip", "netns", "del", probe], check=True)
    return None


def require_netns() -> None:
    """Skip the calling test with the reason when namespaces cannot be made.

    With `TSPACE_REQUIRE_NETNS=1` in the environment (CI) it fails instead:
    there, a skipped multi-host test would pass unnoticed.
    """
    import pytest  # here: benchmarks use this module without pytest installed

    reason = netns_unavailable()
    if reason is None:
        return
    if os.environ.get(REQUIRE) == "1":
        pytest.fail(f"{reason}, and {REQUIRE}=1 requires the multi-host tests to run")
    pytest.skip(reason)


def _ip(*args: str) -> None:
    """Run one `ip` command; raise with its stderr if it fails."""
    done = subprocess.run(["ip", *args], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip()}")


class Proc:
    """A process running in a host's namespace, in its own process group, logging to a file."""

    def __init__(self, host: Host, name: str, argv: Sequence[str]) -> None:
        self.host, self.name = host, name
        self.log = host.net.workdir / f"{host.name}-{name}.log"
        with open(self.log, "ab") as log:
            self.popen = subprocess.Popen(
                ["ip", "netns", "exec", host.netns, *argv],
                cwd=REPO,
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )

    def alive(self) -> bool:
        """Return True while the process runs."""
        return self.popen.poll() is None

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 10.0) -> int:
        """Send `sig`, wait for the exit (SIGKILL after `timeout`) and return the exit code."""
        if self.popen.poll() is None:
            self.popen.send_signal(sig)
        try:
            return self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.popen.pid, signal.SIGKILL)
            return self.popen.wait()

    def logs(self) -> str:
        """Return what the process printed."""
        return self.log.read_text(errors="replace")


class Host:
    """One namespace: a host with an address on the hub's subnet and the processes it runs."""

    def __init__(self, net: Network, name: str, index: int) -> None:
        self.net, self.name = net, name
        self.netns = f"{net.token}-{name}"
        self.address = f"{SUBNET}.{index + 2}"
        self.hub_dev = f"h{index}"
        self.endpoint = f"tcp/{self.address}:{PORT}"
        self.control = f"unixsock-stream/{net.workdir / f'{name}.sock'}"
        self.procs: list[Proc] = []

    def popen(self, name: str, argv: Sequence[str]) -> Proc:
        """Start `argv` in this host (its log is `WORKDIR/HOST-NAME.log`)."""
        proc = Proc(self, name, argv)
        self.procs.append(proc)
        return proc

    def serve(
        self, *, store: bool = True, connect: Sequence[Host] = (), args: Sequence[str] = ()
    ) -> Proc:
        """Start `tspace serve` here: a router meshed with `connect`'s routers, and a store.

        It is configured as docs/deployment.md says (`deploy/multihost/router.json5`),
        listens on the host's address and on its `control` socket, persists
        under `WORKDIR/HOST-data`, and is waited for: returns once its router
        (and, with a store, the store) answers through `control`.
        """
        argv = [sys.executable, "-m", "space.cli", "serve", "--config", str(ROUTER_CONFIG)]
        argv += ["--listen", f"tcp/0.0.0.0:{PORT}", "--listen", self.control]
        argv += [x for peer in connect for x in ("--connect", peer.endpoint)]
        argv += ["--data", str(self.net.workdir / f"{self.name}-data"), *args]
        if not store:
            argv.append("--no-store")
        proc = self.popen("serve", argv)
        self.net.wait(lambda: self._answers(proc, store), 30, f"tspace serve on {self.name}")
        return proc

    def _answers(self, proc: Proc, store: bool) -> bool:
        if not proc.alive():
            raise RuntimeError(f"tspace serve on {self.name} exited: {proc.logs()}")
        try:
            with TripleSpace.open(self.control, space="ping") as ts:
                if store:
                    ts.snapshot(timeout=1.0)
            return True
        except SpaceError:
            return False

    def agent(
        self, module: str, *, space: str, robot: str | None = None, args: Sequence[str] = ()
    ) -> Proc:
        """Start `python -m agents.MODULE` here, a client of this host's own router."""
        argv = [sys.executable, "-m", f"agents.{module}", "--connect", f"tcp/127.0.0.1:{PORT}"]
        argv += ["--space", space, *(["--robot", robot] if robot else []), *args]
        return self.popen(f"{module}-{robot or space}", argv)

    def cut(self) -> None:
        """Take this host's link down (the hub's end: its cable is pulled)."""
        _ip("-n", self.net.hub, "link", "set", self.hub_dev, "down")

    def restore(self) -> None:
        """Bring this host's link up again."""
        _ip("-n", self.net.hub, "link", "set", self.hub_dev, "up")

    @contextmanager
    def outage(self, seconds: float) -> Iterator[None]:
        """Cut the link, run the block, keep it cut until `seconds` passed, then restore it."""
        end = time.monotonic() + seconds
        self.cut()
        try:
            yield
            time.sleep(max(0.0, end - time.monotonic()))  # the outage itself is the point
        finally:
            self.restore()

    def vanish(self) -> None:
        """Lose the host as in a power failure: its link goes first, then every process dies.

        No goodbye reaches the other hosts; they notice through Zenoh's lease.
        """
        _ip("-n", self.net.hub, "link", "del", self.hub_dev)
        self.kill_all()

    def kill_all(self) -> None:
        """SIGKILL every process of the namespace and reap the ones started here."""
        for proc in self.procs:
            if proc.alive():
                os.killpg(proc.popen.pid, signal.SIGKILL)
        for pid in self.pids():
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass  # exited between listing and killing
        for proc in self.procs:
            proc.popen.wait()

    def pids(self) -> list[int]:
        """Return the pids of every process in this namespace."""
        done = subprocess.run(["ip", "netns", "pids", self.netns], capture_output=True, text=True)
        return [int(x) for x in done.stdout.split()]


class Network:
    """A hub namespace with a bridge, and one namespace per host on it; a context manager.

    Args:
        names: the hosts' short names (addresses `10.47.0.2`, `.3`, ... in that order).
        workdir: where logs, data directories and control sockets go (keep the
            path short: Unix socket paths are limited to 107 bytes).
        sysctls: kernel settings of every host's network stack, e.g.
            `{"net.ipv4.tcp_rto_max_ms": "1000"}` (see docs/deployment.md).
    """

    def __init__(
        self, names: Sequence[str], workdir: Path, sysctls: dict[str, str] | None = None
    ) -> None:
        self.token = f"ts{uuid.uuid4().hex[:8]}"
        self.hub = f"{self.token}-hub"
        self.workdir = workdir
        self.sysctls = dict(sysctls or {})
        self.hosts = {name: Host(self, name, i) for i, name in enumerate(names)}
        self._made: list[str] = []

    def __getitem__(self, name: str) -> Host:
        return self.hosts[name]

    def __enter__(self) -> Network:
        try:
            self.open()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def open(self) -> None:
        """Make the hub and the hosts (blocking, a few `ip` calls per host)."""
        self.workdir.mkdir(parents=True, exist_ok=True)
        self._add_netns(self.hub)
        _ip("-n", self.hub, "link", "add", "br0", "type", "bridge")
        _ip("-n", self.hub, "link", "set", "br0", "up")
        for host in self.hosts.values():
            self._add_netns(host.netns)
            _ip("-n", host.netns, "link", "set", "lo", "up")
            for key, value in self.sysctls.items():
                _ip("netns", "exec", host.netns, "sysctl", "-q", "-w", f"{key}={value}")
            self._attach(host)

    def _add_netns(self, name: str) -> None:
        _ip("netns", "add", name)
        self._made.append(name)

    def _attach(self, host: Host) -> None:
        """Give the host an `eth0` whose peer is `hub_dev` on the bridge, both up."""
        peer = ("peer", "name", "eth0", "netns", host.netns)
        _ip("-n", self.hub, "link", "add", host.hub_dev, "type", "veth", *peer)
        _ip("-n", self.hub, "link", "set", host.hub_dev, "master", "br0", "up")
        _ip("-n", host.netns, "addr", "add", f"{host.address}/24", "dev", "eth0")
        _ip("-n", host.netns, "link", "set", "eth0", "up")

    def close(self) -> None:
        """Kill every process in every host, then delete every namespace made.

        Raises:
            RuntimeError: a namespace could not be deleted (after trying them all).
        """
        for host in self.hosts.values():
            if host.netns in self._made:
                host.kill_all()
        failed = []
        for name in reversed(self._made):
            done = subprocess.run(["ip", "netns", "del", name], capture_output=True, text=True)
            if done.returncode != 0:
                failed.append(f"{name}: {done.stderr.strip()}")
        self._made.clear()
        if failed:
            raise RuntimeError(f"namespaces left behind: {'; '.join(failed)}")

    def wait(self, condition: Callable[[], object], timeout: float, what: str) -> None:
        """Poll `condition()` until true; raise TimeoutError after `timeout` seconds."""
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise TimeoutError(f"timed out after {timeout} s waiting for {what}")
            time.sleep(0.05)
