"""A secure space over two hosts (network namespaces): a server, and robot2 with its router.

Each host runs its router in secure mode, as docs/deployment.md lays it out:
the server `tspace serve --secure` (store, listening on its address with a
certificate naming it), robot2 `tspace serve --no-store --secure --identity
router.robot2` connected to it over mTLS. What robot2's host may say passes
two routers' access control and the store's guard: its agents write robot2's
facts, not robot1's; and even robot2's router certificate, used straight
against the server (the host taken over), cannot speak for robot1's agents.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest
from netns import PORT, REPO, Host, Network, require_netns

from space import _certs

pytestmark = pytest.mark.netns

DEVICES = """@prefix ac: <https://w3id.org/tspace/selfconfig#> .
ac:robot1 ac:has_device ac:robot1_battery . ac:robot2 ac:has_device ac:robot2_battery .
ac:robot1_battery ac:charge_percent 90 . ac:robot2_battery ac:charge_percent 90 .
"""
ROBOT1_EMPTY = """@prefix ac: <https://w3id.org/tspace/selfconfig#> .
ac:robot1_battery ac:charge_percent 0 ."""
ROBOT2_LOW = """@prefix ac: <https://w3id.org/tspace/selfconfig#> .
ac:robot2_battery ac:charge_percent 20 ."""


def run(host: Host, *argv: str, stdin: str | None = None) -> subprocess.CompletedProcess:
    """Run a command in `host`'s namespace to completion."""
    return subprocess.run(
        ["ip", "netns", "exec", host.netns, *argv],
        cwd=REPO,
        input=stdin,
        capture_output=True,
        text=True,
        timeout=60,
    )


def tspace(host: Host, certs: Path, identity: str, *args: str, stdin: str | None = None):
    secure = ["--secure", str(certs), "--identity", identity, "--space", "s"]
    return run(host, sys.executable, "-m", "space.cli", *args, *secure, stdin=stdin)


def until_ok(host: Host, certs: Path, identity: str, *args: str, stdin: str | None = None):
    """Retry a tspace command until it succeeds (routers and store starting); fail after 60 s."""
    deadline = time.monotonic() + 60
    while True:
        done = tspace(host, certs, identity, *args, stdin=stdin)
        if done.returncode == 0 or time.monotonic() > deadline:
            return done
        time.sleep(0.5)


def charges(host: Host, certs: Path) -> str:
    done = tspace(host, certs, "operator", "query", "-t", "?s ac:charge_percent ?o", "-f", "json")
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_a_robot_host_speaks_only_for_its_own_robot(tmp_path):
    require_netns()
    with Network(["server", "robot2"], tmp_path / "net") as net:
        server, robot2 = net["server"], net["robot2"]
        certs = tmp_path / "certs"
        _certs.init_authority(certs)
        _certs.issue(certs, "store", _certs.hosts_for("store", [server.address]))
        for name in ("router.robot2", "operator", "hw_monitor.robot2"):
            _certs.issue(certs, name, _certs.hosts_for(name))
        uplink = f"tls/{server.address}:{PORT}"
        local = f"tls/127.0.0.1:{PORT}"
        serve = [sys.executable, "-m", "space.cli", "serve", "--secure", str(certs)]
        server.popen(
            "serve",
            [*serve, "--listen", uplink, "--listen", local, "--data", str(tmp_path / "data")],
        )
        loaded = until_ok(server, certs, "operator", "write", "-", stdin=DEVICES)
        assert loaded.returncode == 0, loaded.stderr + server.procs[0].logs()
        robot2.popen(
            "router",
            [
                *serve,
                "--identity",
                "router.robot2",
                "--no-store",
                "--connect",
                uplink,
                "--listen",
                local,
            ],
        )

        # robot2's agent, through its host's router: its own battery, yes; robot1's, no.
        own = until_ok(robot2, certs, "hw_monitor.robot2", "write", "-", stdin=ROBOT2_LOW)
        assert own.returncode == 0, own.stderr + robot2.procs[0].logs()
        other = tspace(robot2, certs, "hw_monitor.robot2", "write", "-", stdin=ROBOT1_EMPTY)
        assert other.returncode == 1
        assert "refused hw_monitor.robot2: may not write ac:robot1_battery" in other.stderr

        # robot2's host taken over: its router's certificate, straight to the server, under
        # robot1's agent's name or its own, gets nothing through the server's router
        # (a router writes nothing itself), while robot2's agent's key works that way.
        forge = [
            sys.executable,
            str(REPO / "tests" / "programs" / "forge_write.py"),
            uplink,
            str(certs),
        ]
        direct = run(
            robot2, *forge, "hw_monitor.robot2", "tspace/s/@/write/hw_monitor.robot2", ROBOT2_LOW
        )
        assert direct.stdout.startswith("replies 1"), direct.stdout + direct.stderr
        forge.append("router.robot2")
        as_robot1 = run(robot2, *forge, "tspace/s/@/write/hw_monitor.robot1", ROBOT1_EMPTY)
        assert as_robot1.returncode == 0, as_robot1.stderr
        assert as_robot1.stdout.startswith("replies 0"), as_robot1.stdout
        as_itself = run(robot2, *forge, "tspace/s/@/write/router.robot2", ROBOT1_EMPTY)
        assert as_itself.stdout.startswith("replies 0"), as_itself.stdout + as_itself.stderr

        # Plain TCP to the server is no way in either.
        plain = run(
            robot2,
            sys.executable,
            "-m",
            "space.cli",
            "query",
            "-t",
            "?s ?p ?o",
            "--connect",
            f"tcp/{server.address}:{PORT}",
            "--space",
            "s",
        )
        assert plain.returncode == 1 and "no Zenoh router reachable" in plain.stderr

        state = charges(server, certs)
        assert '"90"' in state and '"20"' in state and '"0"' not in state, state
        assert "refused hw_monitor.robot2" in server.procs[0].logs()
