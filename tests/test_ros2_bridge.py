"""The ROS 2 bridge as a process, against the stand-in rmw_zenoh robot (tests/ros2robot.py)."""

from __future__ import annotations

import json
import struct
import subprocess
import sys
import time
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
import zenoh
from agentprocs import knowledge, value
from rdflib import Literal, Namespace
from ros2robot import HASH, typestore
from rosbags.typesys import Stores, get_typestore

from agents.ros2.graph import Graph
from agents.ros2.rmw import EntityKind
from conftest import AC_NS, REPO, wait_for

AC = Namespace(AC_NS)
MAPPING = REPO / "deploy" / "hospital-ros2-mapping.toml"
BATTERY_KEY = (
    "0/robot1/battery_state/sensor_msgs::msg::dds_::BatteryState_/"
    + HASH["sensor_msgs/msg/BatteryState"]
)


class StandIn:
    """The stand-in robot as a child process, with what it received."""

    def __init__(self, endpoint: str, tmp: Path, *args: str) -> None:
        self.record = tmp / "robot.jsonl"
        self.log = tmp / "robot.log"
        argv = [sys.executable, str(REPO / "tests" / "ros2robot.py"), "--connect", endpoint]
        with open(self.log, "ab") as log:
            self.proc = subprocess.Popen(
                [*argv, "--record", str(self.record), *args],
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )

    def received(self) -> list[dict]:
        if not self.record.exists():
            return []
        return [json.loads(line) for line in self.record.read_text().splitlines() if line]

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


@pytest.fixture
def space(ts):
    ts.write(knowledge())
    return ts


@pytest.fixture
def standin(server, tmp_path):
    robots: list[StandIn] = []

    def start(*args: str) -> StandIn:
        robots.append(StandIn(server.endpoint, tmp_path, *args))
        return robots[-1]

    yield start
    for robot in robots:
        robot.close()


def bridge(launch, *args: str):
    return launch.start("ros2", "--mapping", str(MAPPING), "--tick", "0.05", *args)


def mode(ts, device: str) -> str | None:
    found = value(ts, AC[device], AC.actual_mode)
    return None if found is None else str(found)


def test_battery_state_becomes_the_robots_battery_facts(space, launch, standin):
    robot = standin("--charge", "62", "--rate", "20", "--warn", "laser")
    proc = bridge(launch)
    wait_for(lambda: value(space, AC.robot1_battery, AC.charge_percent) == Literal(60), 20,
             "charge 60 from BatteryState", proc.logs)  # fmt: skip
    assert value(space, AC.robot1_battery, AC.battery_level) == Literal("normal")
    # Diagnostics: faults of every mapped device, modes of the unmanaged ones.
    wait_for(lambda: mode(space, "robot1_wheels") == "active", 10, "wheels' mode", proc.logs)
    assert value(space, AC.robot1_laser, AC.fault) == Literal("warning")
    assert value(space, AC.robot1_wheels, AC.fault) == Literal("none")
    # The managed nodes report their lifecycle state: active.
    wait_for(lambda: mode(space, "robot1_screen") == "active", 10, "screen's mode", proc.logs)
    assert value(space, AC.robot1_screen, AC.ros_status) == Literal("ok")
    robot.close()


def test_running_modes_drive_lifecycle_transitions_and_the_node_reports(space, launch, standin):
    robot = standin()
    proc = bridge(launch)
    wait_for(lambda: mode(space, "robot1_speakers") == "active", 20, "speakers up", proc.logs)
    for device in ("robot1_screen", "robot1_speakers", "robot1_microphone"):
        space.write([(AC[device], AC.running_mode, Literal("stand-by"))])
    for device in ("robot1_screen", "robot1_speakers", "robot1_microphone"):
        wait_for(lambda d=device: mode(space, d) == "stand-by", 10, f"{device} inactive", proc.logs)
    calls = [r for r in robot.received() if r.get("service", "").endswith("/change_state")]
    store = typestore()
    transitions = {
        (r["service"], store.deserialize_cdr(bytes.fromhex(r["payload"]),
                                             "lifecycle_msgs/srv/ChangeState_Request").transition.id)
        for r in calls
    }  # fmt: skip
    devices = ("screen", "speakers", "microphone")
    assert transitions == {(f"/robot1/{n}/change_state", 4) for n in devices}
    space.write([(AC.robot1_screen, AC.running_mode, Literal("disabled"))])
    wait_for(lambda: mode(space, "robot1_screen") == "disabled", 10, "screen cleaned up")
    space.write([(AC.robot1_screen, AC.running_mode, Literal("active"))])
    wait_for(lambda: mode(space, "robot1_screen") == "active", 10, "screen configured, activated")


def test_an_unanswered_lifecycle_call_is_reported_then_retried(space, launch, standin):
    standin("--managed", "screen", "speakers")  # no microphone node yet
    proc = bridge(launch)
    wait_for(
        lambda: str(value(space, AC.robot1_microphone, AC.ros_status) or "").startswith(
            "/robot1/microphone/get_state: no answer"
        ),
        20,
        "a timeout reported",
        proc.logs,
    )
    assert mode(space, "robot1_microphone") is None
    assert proc.alive()
    # The microphone's node comes up: the bridge sees its service and asks at once.
    standin("--managed", "microphone", "--unmanaged")
    wait_for(lambda: mode(space, "robot1_microphone") == "active", 20, "microphone", proc.logs)
    assert value(space, AC.robot1_microphone, AC.ros_status) == Literal("ok")
    wait_for(lambda: "managed node /robot1/microphone is up" in proc.logs(), 10, "the log line")
    # SIGTERM: the drivers stop, the node leaves the graph, the process exits cleanly.
    assert proc.stop() == 0


def test_what_the_bridge_sends_decodes_with_rosbags_and_carries_an_attachment(
    space, launch, standin
):
    started_ns = time.time_ns()
    robot = standin()
    proc = bridge(launch)
    wait_for(lambda: mode(space, "robot1_screen") == "active", 20, "bridge up", proc.logs)
    space.write([(AC.robot1_base, AC.motion_speed, Literal("low"))])
    space.write([(AC.robot1, AC.current_task, AC.task_charging)])

    def sent(kind: str) -> list[dict]:
        return [r for r in robot.received() if kind in (r.get("topic"), r.get("service"))]

    store = typestore()
    low = next(
        float(value(space, level, AC.meters_per_second))
        for level in space.query((None, AC.level, Literal("low"))).subjects()
        if value(space, level, AC.meters_per_second) is not None
    )

    def limits() -> list[float]:
        return [
            store.deserialize_cdr(bytes.fromhex(r["payload"]), r["type"]).speed_limit
            for r in sent("/robot1/speed_limit")
        ]

    wait_for(lambda: low in limits() and len(sent("/robot1/current_task")) >= 2, 10,
             "low speed limit and task received", proc.logs)  # fmt: skip

    def speed_parameters() -> list[float]:
        return [
            p.value.double_value
            for r in sent("/robot1/controller_server/set_parameters")
            for p in store.deserialize_cdr(
                bytes.fromhex(r["payload"]), r["type"] + "_Request"
            ).parameters
        ]

    wait_for(lambda: low in speed_parameters(), 10, "the controller's speed parameter set")
    jazzy = get_typestore(Stores.ROS2_JAZZY)
    writers: dict[str, list[tuple[int, bytes]]] = {}  # key -> (sequence, gid) in order
    parameters: list[float] = []
    for record in robot.received():
        payload, att = bytes.fromhex(record["payload"]), bytes.fromhex(record["attachment"])
        ros_type = record["type"] + ("_Request" if "service" in record else "")
        message = store.deserialize_cdr(payload, ros_type)
        assert bytes(store.serialize_cdr(message, ros_type)) == payload  # byte for byte
        # rmw_zenoh's attachment: int64 sequence, int64 source time (ns), length 16, GID.
        sequence, stamp, length = struct.unpack_from("<qqB", att)
        assert len(att) == 33 and length == 16
        assert started_ns <= stamp <= time.time_ns()
        writers.setdefault(record["key"], []).append((sequence, att[17:]))
        assert record["key"].endswith(HASH[record["type"]])
        if record.get("topic") == "/robot1/speed_limit":
            assert message.percentage is False
            assert message.header.stamp.sec > 0
        if record.get("topic") == "/robot1/current_task":
            assert bytes(jazzy.serialize_cdr(message, "std_msgs/msg/String")) == payload
        if record.get("service") == "/robot1/controller_server/set_parameters":
            (parameter,) = message.parameters
            assert parameter.name == "FollowPath.max_vel_x"
            assert parameter.value.type == 3  # PARAMETER_DOUBLE
            parameters.append(parameter.value.double_value)
    tasks = [
        store.deserialize_cdr(bytes.fromhex(r["payload"]), r["type"]).data
        for r in sent("/robot1/current_task")
    ]
    assert tasks[-1] == "Charging"
    assert parameters[-1] == pytest.approx(low)
    # Each writer numbers its samples 1, 2, 3... (clients per request) under one GID.
    for key, seen in writers.items():
        assert [n for n, _ in seen] == list(range(1, len(seen) + 1)), key
        assert len({gid for _, gid in seen}) == 1, key
    assert len({seen[0][1] for seen in writers.values()}) == len(writers)


def test_malformed_cdr_and_unknown_types_are_logged_and_skipped(space, launch, server):
    proc = bridge(launch)
    with zenoh.open(client_config(server.endpoint)) as session:
        wait_for(lambda: "ROS 2 node" in proc.logs(), 20, "bridge up", proc.logs)
        session.put(BATTERY_KEY, b"\x00\x01\x00\x00\x05")  # truncated
        session.put(BATTERY_KEY, b"garbage")  # no encapsulation header
        other = "0/robot1/battery_state/std_msgs::msg::dds_::String_/" + HASH["std_msgs/msg/String"]
        session.put(other, b"\x00\x01\x00\x00\x03\x00\x00\x00hi\x00")
        wait_for(lambda: "unexpected type std_msgs/msg/String" in proc.logs(), 10, "type logged")
        wait_for(lambda: proc.logs().count("malformed message skipped") >= 2, 10, "CDR logged")
        # Still alive and still bridging: a good message after the bad ones is taken.
        store = get_typestore(Stores.ROS2_JAZZY)
        msg = store.types["sensor_msgs/msg/BatteryState"]
        good = bytes(store.serialize_cdr(battery(store, msg, 0.31), "sensor_msgs/msg/BatteryState"))
        # Its attachment is not rmw_zenoh's 33 bytes: said once, the message still taken.
        session.put(BATTERY_KEY, good, attachment=b"\x01\x02")
        wait_for(lambda: value(space, AC.robot1_battery, AC.charge_percent) == Literal(30), 10)
        said = "expected 33 (an older rmw_zenoh?); messages still taken"
        wait_for(lambda: said in proc.logs(), 10, "the attachment's line")
    assert proc.alive()


def test_the_bridge_is_on_the_ros_graph(space, launch, server):
    proc = bridge(launch)
    with zenoh.open(client_config(server.endpoint)) as session:

        def tokens() -> list[str]:
            return [str(r.ok.key_expr) for r in session.liveliness().get("@ros2_lv/0/**") if r.ok]

        wait_for(lambda: len(tokens()) >= 1 + 2 + 2 + 7, 20, "bridge's tokens", proc.logs)
        found = tokens()
    zid_chunks = {t.split("/")[2] for t in found}
    assert len(zid_chunks) == 1
    kinds = sorted(t.split("/")[5] for t in found)
    assert kinds.count("NN") == 1 and kinds.count("MS") == 2 and kinds.count("MP") == 2
    assert kinds.count("SC") == 7
    node = next(t for t in found if t.split("/")[5] == "NN")
    assert node.split("/")[6:] == ["%", "%robot1", "tspace_bridge"]
    sub = next(t for t in found if "%robot1%battery_state" in t)
    assert sub.split("/")[5:] == [
        "MS", "%", "%robot1", "tspace_bridge", "%robot1%battery_state",
        "sensor_msgs::msg::dds_::BatteryState_", HASH["sensor_msgs/msg/BatteryState"],
        "::,10:,:,:,,",
    ]  # fmt: skip
    client = next(t for t in found if "%robot1%screen%change_state" in t)
    assert client.split("/")[10:12] == [
        "lifecycle_msgs::srv::dds_::ChangeState_",
        HASH["lifecycle_msgs/srv/ChangeState"],
    ]


def test_a_bad_mapping_is_a_clear_error(space, launch, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[[battery]]\ntopic = "battery_state"\ndevice = 3\n')
    proc = launch.start("ros2", "--mapping", str(bad))
    assert proc.proc is not None and proc.proc.wait(timeout=20) == 1
    assert "[[battery]] device must be a non-empty string, got 3" in proc.logs()


def client_config(endpoint: str) -> zenoh.Config:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    return conf


def battery(store, cls, fraction: float):
    t = store.types
    header = t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=1, nanosec=0),
                                      frame_id="")  # fmt: skip
    empty = np.array([], dtype=np.float32)
    return cls(header=header, voltage=0.0, temperature=0.0, current=0.0, charge=0.0,
               capacity=0.0, design_capacity=0.0, percentage=fraction, power_supply_status=2,
               power_supply_health=0, power_supply_technology=0, present=True,
               cell_voltage=empty, cell_temperature=empty, location="",
               serial_number="")  # fmt: skip


PLACE_AND_POSE = """
[ros]
namespace = "/{robot}"
[[place]]
topic = "place"
[[pose]]
topic = "pose"
max_rate = 2.0
"""


def test_a_100hz_topic_is_rate_limited_and_change_filtered(space, launch, server, tmp_path):
    mapping = tmp_path / "mapping.toml"
    mapping.write_text(PLACE_AND_POSE)
    proc = launch.start("ros2", "--mapping", str(mapping), "--tick", "0.05")
    store = get_typestore(Stores.ROS2_JAZZY)
    writes: list[object] = []
    sub = space.subscribe((AC.robot1, AC.position_x, None), lambda c: writes.extend(c.added))
    with zenoh.open(client_config(server.endpoint)) as session:
        wait_for(lambda: "ROS 2 node" in proc.logs(), 20, "bridge up", proc.logs)
        pose_key = "0/robot1/pose/geometry_msgs::msg::dds_::PoseStamped_/" + (
            "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8"
        )
        place_key = "0/robot1/place/std_msgs::msg::dds_::String_/" + HASH["std_msgs/msg/String"]

        def pose(x: float) -> bytes:
            t = store.types
            msg = t["geometry_msgs/msg/PoseStamped"](
                header=t["std_msgs/msg/Header"](
                    stamp=t["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="map"
                ),
                pose=t["geometry_msgs/msg/Pose"](
                    position=t["geometry_msgs/msg/Point"](x=x, y=2.0, z=0.0),
                    orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                ),
            )
            return bytes(store.serialize_cdr(msg, "geometry_msgs/msg/PoseStamped"))

        def place(name: str) -> bytes:
            msg = store.types["std_msgs/msg/String"](data=name)
            return bytes(store.serialize_cdr(msg, "std_msgs/msg/String"))

        # 100 Hz of the same pose: one write.
        for _ in range(50):
            session.put(pose_key, pose(1.0))
            time.sleep(0.01)
        wait_for(lambda: value(space, AC.robot1, AC.position_x) is not None, 10, "first pose")
        assert len(writes) == 1
        # 100 Hz for one second of a moving robot: at most 2 writes a second, and the
        # last pose is the one the space keeps.
        start = time.monotonic()
        for i in range(100):
            session.put(pose_key, pose(1.0 + (i + 1) * 0.01))
            time.sleep(0.01)
        elapsed = time.monotonic() - start
        # By value: a store may keep a decimal in its canonical form ("2.0" for "2.00").
        wait_for(lambda: _number(value(space, AC.robot1, AC.position_x)) == Decimal("2.00"), 10,
                 "the last pose written", proc.logs)  # fmt: skip
        assert 2 <= len(writes) <= 1 + 2 * (elapsed + 1), writes
        # A named place becomes the location; an unknown one is skipped.
        session.put(place_key, place("nowhere"))
        session.put(place_key, place("room_101"))
        wait_for(lambda: value(space, AC.robot1, AC.location) == AC.room_101, 10, "location")
    sub.close()


def test_domains_and_namespaces_keep_robots_apart(space, launch, standin):
    standin("--domain", "3", "--namespace", "/robot2", "--charge", "42")
    standin("--domain", "0", "--namespace", "/robot2", "--charge", "91")
    proc = launch.start("ros2", "--mapping", str(MAPPING), "--robot", "robot2", "--domain", "3")
    wait_for(lambda: value(space, AC.robot2_battery, AC.charge_percent) == Literal(40), 20,
             "robot2's battery on domain 3", proc.logs)  # fmt: skip
    wait_for(lambda: mode(space, "robot2_screen") == "active", 10, "robot2's screen")
    assert "ROS 2 node /robot2/tspace_bridge on domain 3" in proc.logs()
    for _ in range(20):  # the domain-0 robot's 91 % never shows
        assert value(space, AC.robot2_battery, AC.charge_percent) == Literal(40)
        time.sleep(0.05)


def test_the_graph_sees_the_robots_nodes_and_topics(server, standin):
    standin()
    with zenoh.open(client_config(server.endpoint)) as session:
        graph = Graph().open(session, 0)
        try:
            # the stand-in's entities arrive one liveliness token at a time: wait for the last
            nodes = {"/robot1/microphone", "/robot1/robot_driver", "/robot1/screen"}
            nodes.add("/robot1/controller_server")
            wait_for(lambda: nodes <= set(graph.nodes()), 20, "the robot's nodes")
            wait_for(lambda: graph.offers(EntityKind.SERVICE, "/robot1/screen/change_state"), 20)
            wanted = {"/robot1/battery_state", "/robot1/speed_limit"}
            wait_for(lambda: wanted <= graph.topics().keys(), 20, "the robot's topics")
            topics = graph.topics()
            assert topics["/robot1/battery_state"] == {"sensor_msgs/msg/BatteryState"}
            assert topics["/robot1/speed_limit"] == {"nav2_msgs/msg/SpeedLimit"}
            servers = graph.offers(EntityKind.SERVICE, "/robot1/screen/change_state")
            assert [s.endpoint.ros_type for s in servers] == ["lifecycle_msgs/srv/ChangeState"]
        finally:
            graph.close()


def test_a_state_changed_behind_the_bridges_back_is_led_back(space, launch, standin, server):
    robot = standin()
    proc = bridge(launch)
    wait_for(lambda: mode(space, "robot1_screen") == "active", 20, "screen active", proc.logs)
    store = typestore()
    key = (
        "0/robot1/screen/change_state/lifecycle_msgs::srv::dds_::ChangeState_/"
        + (HASH["lifecycle_msgs/srv/ChangeState"])
    )
    request = store.types["lifecycle_msgs/srv/ChangeState_Request"](
        transition=store.types["lifecycle_msgs/msg/Transition"](id=4, label="deactivate")
    )
    # As `ros2 lifecycle set /robot1/screen deactivate` would, from another client.
    with zenoh.open(client_config(server.endpoint)) as session:
        attachment = struct.pack("<qqB", 1, time.time_ns(), 16) + bytes(16)
        replies = list(
            session.get(
                key,
                payload=bytes(
                    store.serialize_cdr(request, "lifecycle_msgs/srv/ChangeState_Request")
                ),
                attachment=attachment,
                target=zenoh.QueryTarget.ALL_COMPLETE,
                timeout=5,
            )
        )
    assert [r.ok is not None for r in replies] == [True]

    def activations() -> int:
        return sum(
            1
            for r in robot.received()
            if r.get("service") == "/robot1/screen/change_state"
            and store.deserialize_cdr(
                bytes.fromhex(r["payload"]), "lifecycle_msgs/srv/ChangeState_Request"
            ).transition.id
            == 3
        )

    # The space commands active: within a poll the bridge sees it and activates again.
    wait_for(lambda: activations() >= 1, 15, "the bridge reactivating the screen", proc.logs)
    wait_for(lambda: mode(space, "robot1_screen") == "active", 10, "screen active again")


def _number(term: object) -> object:
    return term.toPython() if isinstance(term, Literal) else None
