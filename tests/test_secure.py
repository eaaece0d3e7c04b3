"""A secure space: mutual TLS on every link, identities from certificates, the policy enforced.

A real `tspace serve --secure` (router with Zenoh access control from
deploy/policy.toml, store with its write guard) on a free loopback port; the
attacks come from real Zenoh sessions holding another robot's certificate.
"""

from __future__ import annotations

import stat
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh
from cryptography import x509
from cryptography.x509.oid import NameOID
from rdflib import OWL, Literal, Namespace

from conftest import AC_NS, REPO, Server, free_port, tspace_cmd, wait_for
from space import (
    ChangesetRejected,
    QueryError,
    SpaceError,
    SpaceUnavailable,
    TripleSpace,
    _certs,
    escape_key_chunk,
    load_identity,
)
from space.changeset import Changeset, pack, unpack
from space.zconfig import make_config

AC = Namespace(AC_NS)
NAMES = [
    "router",
    "store",
    "operator",
    "reasoner",
    "hmi",
    "hw_monitor.robot1",
    "hw_monitor.robot2",
    "behavior.robot2",
]
DEVICES = [
    (AC.robot1, AC.has_device, AC.robot1_battery),
    (AC.robot2, AC.has_device, AC.robot2_battery),
    (AC.robot1_battery, AC.battery_level, Literal("high")),
    (AC.robot2_battery, AC.battery_level, Literal("high")),
]


def make_certs(directory: Path, names: list[str] = NAMES) -> Path:
    _certs.init_authority(directory)
    for name in names:
        _certs.issue(directory, name, _certs.hosts_for(name))
    return directory


class SecureServer(Server):
    """`tspace serve --secure DIR` on a free TLS port; `answers` as the operator."""

    def __init__(self, data_dir: Path, certs: Path, *extra: str) -> None:
        super().__init__(data_dir, "--secure", str(certs), *extra)
        self.endpoint = f"tls/127.0.0.1:{self.port}"
        self.certs = certs

    def _answers(self) -> bool:
        assert self.proc is not None
        if self.proc.poll() is not None:
            pytest.fail(f"tspace serve exited with {self.proc.returncode}: {self.logs()}")
        try:
            with self.open("operator", "ping") as ts:
                ts.snapshot(timeout=1.0)
            return True
        except SpaceError:
            return False

    def open(self, identity: str, space: str) -> TripleSpace:
        return TripleSpace.open(
            self.endpoint,
            space=space,
            agent=identity,
            identity=load_identity(self.certs, identity),
            prefixes={"ac": AC_NS},
        )


@pytest.fixture(scope="module")
def certs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_certs(tmp_path_factory.mktemp("certs"))


@pytest.fixture(scope="module")
def secure(tmp_path_factory: pytest.TempPathFactory, certs: Path) -> Iterator[SecureServer]:
    srv = SecureServer(tmp_path_factory.mktemp("secure") / "data", certs)
    srv.start()
    try:
        yield srv
    finally:
        srv.stop()


@pytest.fixture
def fleet(secure: SecureServer, space_name: str) -> Iterator[TripleSpace]:
    """The operator's handle on a space holding two robots and their batteries."""
    with secure.open("operator", space_name) as ts:
        ts.write(DEVICES)
        yield ts


def raw_session(secure: SecureServer, identity: str) -> zenoh.Session:
    conf = make_config(connect=[secure.endpoint], identity=load_identity(secure.certs, identity))
    return zenoh.open(conf)


def battery(ts: TripleSpace, robot: str) -> set:
    return set(ts.query((AC[f"{robot}_battery"], AC.battery_level, None)).objects())


def test_certs_init_makes_a_ca_and_one_certificate_per_identity_keys_0600(tmp_path):
    directory = tmp_path / "certs"
    cmd = tspace_cmd("certs", "init", str(directory), "--fleet", str(REPO / "deploy/fleet.toml"))
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    expected = {"router", "store", "operator", "reasoner", "fleet_monitor", "hmi"}
    expected |= {"router.robot1", "router.robot2", "router.guide1"} | {
        f"{kind}.{robot}"
        for kind in ("hw_monitor", "nav_monitor", "behavior")
        for robot in ("robot1", "robot2", "guide1")
    }
    made = {p.stem for p in directory.glob("*.pem")} - {"ca"}
    assert made == expected
    for name in made | {"ca"}:
        key = directory / f"{name}.key"
        assert stat.S_IMODE(key.stat().st_mode) == 0o600, key
        cert = x509.load_pem_x509_certificate((directory / f"{name}.pem").read_bytes())
        cns = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
        assert len(cns) == 1 and cns[0].value == (name if name != "ca" else "tspace fleet CA")
    # Run again: everything is kept (a robot's certificate is not silently replaced).
    before = (directory / "hw_monitor.robot1.pem").read_bytes()
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert again.returncode == 0 and "made 0 certificate(s)" in again.stdout
    assert (directory / "hw_monitor.robot1.pem").read_bytes() == before


def test_without_a_certificate_of_the_fleet_nothing_connects(secure, tmp_path):
    plain = f"tcp/127.0.0.1:{secure.port}"
    with pytest.raises(SpaceUnavailable):
        TripleSpace.open(plain, space="s")  # plain TCP on the TLS port
    no_cert = zenoh.Config()
    no_cert.insert_json5("mode", '"client"')
    no_cert.insert_json5("connect/endpoints", f'["{secure.endpoint}"]')
    no_cert.insert_json5("transport/link/tls/root_ca_certificate", f'"{secure.certs / "ca.pem"}"')
    with pytest.raises(zenoh.ZError):
        zenoh.open(no_cert).close()  # TLS, trusting the CA, but showing no certificate
    stranger = make_certs(tmp_path / "other-ca", ["operator"])  # a valid cert of another CA
    with pytest.raises(SpaceUnavailable):
        TripleSpace.open(secure.endpoint, space="s", identity=load_identity(stranger, "operator"))
    # And a secure client will not dial plain TCP at all.
    with pytest.raises(ValueError, match="TLS only"):
        TripleSpace.open(plain, space="s", identity=load_identity(secure.certs, "operator"))


def test_robot2_cannot_write_robot1s_battery_and_the_store_logs_it(secure, fleet, space_name):
    with secure.open("hw_monitor.robot2", space_name) as robot2:
        with pytest.raises(ChangesetRejected, match=r"refused hw_monitor\.robot2"):
            robot2.write([(AC.robot1_battery, AC.battery_level, Literal("empty"))])
        own = (AC.robot2_battery, AC.battery_level)
        robot2.apply([(*own, Literal("low"))], [(*own, Literal("high"))])  # its own: fine
        # Nor by making robot1's battery its own first, or robot2 the same as robot1.
        claim = (AC.robot2, AC.has_device, AC.robot1_battery)
        for triples in (
            [claim],
            [claim, (AC.robot1_battery, AC.battery_level, Literal("empty"))],
            [(AC.robot2, OWL.sameAs, AC.robot1)],
        ):
            with pytest.raises(ChangesetRejected, match="an operator's to write"):
                robot2.write(triples)
    assert battery(fleet, "robot1") == {Literal("high")}
    assert battery(fleet, "robot2") == {Literal("low")}
    assert len(fleet.query((AC.robot2, None, AC.robot1_battery))) == 0
    assert len(fleet.query((AC.robot2, OWL.sameAs, None))) == 0
    wait_for(
        lambda: "refused hw_monitor.robot2: may not write ac:robot1_battery" in secure.logs(),
        10,
        "the store's log line naming the identity",
    )


def test_robot2_cannot_write_under_robot1s_name(secure, fleet, space_name):
    """The key names the writer; the router lets only that certificate use it."""
    forged = Changeset(added=[(AC.robot1_battery, AC.battery_level, Literal("empty"))])
    session = raw_session(secure, "hw_monitor.robot2")
    try:
        for key in (
            f"tspace/{space_name}/@/write/hw_monitor.robot1",
            f"tspace/{space_name}/@/write",
        ):
            session.put(key, forged.encode())
            assert not list(session.get(key, payload=forged.encode(), timeout=1.0))
    finally:
        session.close()
    fleet.write(
        [(AC.robot2, AC.marker, Literal("after"))]
    )  # the store has handled what came before
    assert battery(fleet, "robot1") == {Literal("high")}


def test_robot2_cannot_forge_a_change_notification(secure, fleet, space_name):
    seen: list = []
    raw_seen: list = []
    scoped: list = []
    fleet.subscribe((None, None, None), seen.append)
    fleet.subscribe(None, scoped.append, scope=[(AC.robot1_battery, None), (AC.robot2, None)])
    watcher = raw_session(secure, "hw_monitor.robot1")
    sub = watcher.declare_subscriber(f"tspace/{space_name}/t/**", raw_seen.append)
    session = raw_session(secure, "hw_monitor.robot2")
    try:
        seq = unpack(
            next(
                iter(
                    session.get(
                        f"tspace/{space_name}/@/log",
                        payload=pack({"from": 1, "to": 0}),
                        timeout=5.0,
                    )
                )
            ).ok.payload.to_bytes()
        )["seq"]
        forged = Changeset(added=[(AC.robot1_battery, AC.battery_level, Literal("empty"))])
        forged.seq = seq + 1
        session.put(f"tspace/{space_name}/@/changes", forged.encode())
        part = {**forged.to_wire(), "prev": 0}
        s, p = (escape_key_chunk(f"<{x}>") for x in (AC.robot1_battery, AC.battery_level))
        session.put(f"tspace/{space_name}/@/changes/{s}/{p}", pack(part))
        session.put(f'tspace/{space_name}/t/ac:robot1_battery/ac:battery_level/"empty"', b"")
        session.put(f"tspace/{space_name}/@/seq", pack({"seq": seq + 5}))
        fleet.write([(AC.robot2, AC.marker, Literal("real"))])
        wait_for(
            lambda: any((AC.robot2, AC.marker, Literal("real")) in c.added for c in seen),
            10,
            "the real change",
        )
        wait_for(lambda: any("marker" in str(s.key_expr) for s in raw_seen), 10, "its key")
        wait_for(lambda: any(c.id != forged.id for c in scoped), 10, "the real part")
    finally:
        sub.undeclare()
        watcher.close()
        session.close()
    assert not any(c.id == forged.id for c in seen)
    assert not any(c.id == forged.id for c in scoped)
    assert not any("empty" in str(s.key_expr) for s in raw_seen)
    assert battery(fleet, "robot1") == {Literal("high")}


def test_robot2_cannot_take_another_robots_items(secure, fleet, space_name):
    with secure.open("hw_monitor.robot2", space_name) as robot2:
        with pytest.raises(QueryError, match=r"refused hw_monitor\.robot2"):
            robot2.take((AC.robot1_battery, None, None))
        assert battery(fleet, "robot1") == {Literal("high")}
        taken = robot2.take((AC.robot2_battery, AC.battery_level, None))  # its own
        assert set(taken.objects()) == {Literal("high")}
    assert battery(fleet, "robot2") == set()
    # A take on the bare query key (open to every reader) names no taker: refused too.
    session = raw_session(secure, "hw_monitor.robot2")
    try:
        request = {"op": "take", "template": [AC.robot1_battery.n3(), None, None]}
        replies = list(
            session.get(f"tspace/{space_name}/@/query", payload=pack(request), timeout=5)
        )
        assert len(replies) == 1 and replies[0].err is not None
    finally:
        session.close()
    assert battery(fleet, "robot1") == {Literal("high")}


def test_robot2_cannot_answer_queries_as_a_store(secure, fleet, space_name):
    fake = pack({"seq": 999, "t": [], "i": []})
    session = raw_session(secure, "hw_monitor.robot2")
    answering = [
        session.declare_queryable(key, lambda q: q.reply(q.key_expr, fake))
        for key in (
            f"tspace/{space_name}/@/query",
            f"tspace/{space_name}/@/query/operator",
            f"tspace/{space_name}/t/**",
        )
    ]
    operator = raw_session(secure, "operator")
    try:
        request = pack({"op": "query", "template": [None, None, None]})
        for _ in range(3):  # the fake queryables had time to be declared, were they let through
            replies = [
                r.ok.payload.to_bytes()
                for r in operator.get(
                    f"tspace/{space_name}/@/query/operator", payload=request, timeout=2.0
                )
            ]
            assert len(replies) == 1 and replies[0] != fake
            assert unpack(replies[0])["seq"] != 999
            keys = list(operator.get(f"tspace/{space_name}/t/ac:robot1/**", timeout=2.0))
            assert all(r.ok is not None and r.ok.payload.to_bytes() != fake for r in keys)
            time.sleep(0.3)
    finally:
        for q in answering:
            q.undeclare()
        operator.close()
        session.close()
    assert battery(fleet, "robot1") == {Literal("high")}


def test_only_a_reasoner_writes_inferred_triples_and_the_hmi_only_task_requests(
    secure, fleet, space_name
):
    conclusion = [(AC.robot1, AC.speed, Literal("low"))]
    for name in ("hw_monitor.robot1", "hmi"):
        with secure.open(name, space_name) as ts, pytest.raises(ChangesetRejected, match="infer"):
            ts.apply(inferred_added=conclusion)
    with secure.open("reasoner", space_name) as reasoner:
        reasoner.apply(inferred_added=conclusion)
    assert set(fleet.query((AC.robot1, AC.speed, None), graph="inferred")) == set(conclusion)
    with secure.open("hmi", space_name) as hmi:
        hmi.write([(AC.robot1, AC.requested_task, AC.task_go_to_dock)])
        with pytest.raises(ChangesetRejected, match="refused hmi: may not write ac:battery_level"):
            hmi.write([(AC.robot1_battery, AC.battery_level, Literal("empty"))])
    assert battery(fleet, "robot1") == {Literal("high")}


def test_a_revoked_certificate_is_refused_after_a_restart(tmp_path, certs):
    policy = tmp_path / "policy.toml"
    text = (REPO / "deploy" / "policy.toml").read_text()
    policy.write_text(text.replace("revoked = []", 'revoked = ["hw_monitor.robot2"]', 1))
    srv = SecureServer(tmp_path / "data", certs)
    srv.start()
    try:
        with srv.open("operator", "s") as operator:
            operator.write(DEVICES[:2])
        with srv.open("hw_monitor.robot2", "s") as robot2:
            robot2.write([(AC.robot2_battery, AC.battery_level, Literal("low"))])
        srv.stop()
        srv.extra = (*srv.extra, "--policy", str(policy))
        srv.start()
        with srv.open("hw_monitor.robot2", "s") as robot2:  # TLS still accepts it ...
            with pytest.raises(SpaceUnavailable):  # ... but nothing it says gets through
                robot2.write([(AC.robot2_battery, AC.battery_level, Literal("empty"))], timeout=2)
            with pytest.raises(SpaceUnavailable):
                robot2.query((None, None, None), timeout=2)
        with srv.open("hw_monitor.robot1", "s") as robot1:  # the others go on
            assert battery(robot1, "robot2") == {Literal("low")}
    finally:
        srv.stop()


def test_the_battery_scenario_passes_in_secure_mode(tmp_path):
    directory = tmp_path / "certs"
    launch = REPO / "deploy" / "hospital.toml"
    init = tspace_cmd("certs", "init", str(directory), "--fleet", str(launch))
    assert subprocess.run(init, capture_output=True, timeout=60).returncode == 0
    endpoint = f"tls/127.0.0.1:{free_port()}"
    up = tspace_cmd(
        "up",
        str(launch),
        "--secure",
        str(directory),
        "--listen",
        endpoint,
        "--scenario",
        "battery",
        "--once",
        "--data",
        str(tmp_path / "data"),
        "--hmi-port",
        str(free_port()),
    )
    done = subprocess.run(up, capture_output=True, text=True, timeout=240)
    logs = "\n".join(p.read_text() for p in (tmp_path / "data" / "logs").glob("*.log"))
    assert done.returncode == 0, done.stderr[-3000:] + logs[-3000:]
    assert "scenario battery: completed" in done.stdout + done.stderr
    assert "refused" not in logs, logs


def test_secure_serve_refuses_a_configuration_with_a_plain_endpoint(tmp_path, certs):
    config = REPO / "deploy" / "multihost" / "router.json5"  # listens on tcp/0.0.0.0:7447
    cmd = tspace_cmd(
        "serve", "--secure", str(certs), "--config", str(config), "--data", str(tmp_path / "data")
    )
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    assert done.returncode == 1
    assert "TLS only: use tls/HOST:PORT, not 'tcp/0.0.0.0:7447'" in done.stderr
    assert not (tmp_path / "data").exists()
    elsewhere = tmp_path / "elsewhere"  # no deploy/policy.toml here, and none named
    elsewhere.mkdir()
    cmd = tspace_cmd("serve", "--secure", str(certs), "--data", str(tmp_path / "data"))
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=30, cwd=elsewhere)
    assert done.returncode == 1 and "secure mode needs a policy: --policy FILE" in done.stderr
    assert not (tmp_path / "data").exists()
    missing = subprocess.run(
        tspace_cmd("query", "-t", "?s ?p ?o", "--secure", str(certs), "--identity", "robot9"),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert missing.returncode == 1 and "no identity 'robot9'" in missing.stderr


def test_the_commands_work_with_secure_and_identity(secure, space_name):
    def tspace(*args: str, identity: str = "operator", stdin: str | None = None):
        cmd = tspace_cmd(
            *args,
            "--connect",
            secure.endpoint,
            "--space",
            space_name,
            "--secure",
            str(secure.certs),
            "--identity",
            identity,
        )
        return subprocess.run(cmd, input=stdin, capture_output=True, text=True, timeout=60)

    prefix = f"@prefix ac: <{AC_NS}> .\n"
    devices = prefix + "ac:robot2 ac:has_device ac:robot2_battery .\n"
    assert tspace("write", "-", stdin=devices).returncode == 0
    watch = subprocess.Popen(
        tspace_cmd(
            "watch",
            "?s ac:battery_level ?o",
            "--connect",
            secure.endpoint,
            "--space",
            space_name,
            "--secure",
            str(secure.certs),
        ),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: list[str] = []
    threading.Thread(target=lambda: lines.extend(watch.stdout), daemon=True).start()
    try:
        count = iter(range(1000))

        def watched() -> bool:  # a new reading each time, until the operator's watch shows one
            level = f'ac:robot2_battery ac:battery_level "{next(count)}" .\n'
            done = tspace("write", "-", identity="hw_monitor.robot2", stdin=prefix + level)
            assert done.returncode == 0, done.stderr
            return any(line.startswith("+ ac:robot2_battery ac:battery_level") for line in lines)

        wait_for(watched, 30, "tspace watch --secure to show a write")
        query = tspace("query", "-t", "?s ac:battery_level ?o", identity="hw_monitor.robot1")
        assert query.returncode == 0 and '"0"' in query.stdout  # robot1's agent reads the fleet
        denied = tspace("take", "ac:robot2_battery ?p ?o", identity="hw_monitor.robot1")
        assert denied.returncode == 1 and "refused hw_monitor.robot1" in denied.stderr
        taken = tspace(
            "take", "ac:robot2_battery ac:battery_level ?o", identity="hw_monitor.robot2"
        )
        assert taken.returncode == 0 and '"0"' in taken.stdout, taken.stderr
    finally:
        watch.terminate()
        watch.wait(timeout=10)
