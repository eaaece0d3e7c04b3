"""A stand-in ROS 2 robot on rmw_zenoh's wire format, written from rmw_zenoh's docs/design.md.

It shares no code with the bridge (agents/ros2): keys, liveliness tokens and the
33-byte attachment are spelled out here again, and the type hashes are the
published RIHS01 values, so a mistake in the bridge's wire code shows as a test
failure instead of cancelling out. CDR goes through rosbags.

The robot: `robot_driver` publishes sensor_msgs/BatteryState and
diagnostic_msgs/DiagnosticArray at `--rate` Hz and subscribes to the speed limit
and the current task (charging while the task is Charging); one managed node per
`--managed` device serves lifecycle change_state/get_state; `controller_server`
serves set_parameters. Everything it receives is appended to `--record` as JSON
lines, with the payload and attachment bytes in hex.

    python tests/ros2robot.py --connect tcp/127.0.0.1:7447 --namespace /robot1
"""

from __future__ import annotations

import argparse
import json
import signal
import struct
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import zenoh
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

# Published RIHS01 hashes (Jazzy): see tests/test_ros2_wire.py for where each comes from.
HASH = {
    "sensor_msgs/msg/BatteryState": "RIHS01_4bee5dfce981c98faa6828b868307a0a"
    "73f992ed0789f374ee96c8f840e69741",
    "diagnostic_msgs/msg/DiagnosticArray": "RIHS01_5a8a36efb05fb25070fa0fb3810290c0"
    "e6cd4862b54a8fb975a1ee8dc55a333e",
    "std_msgs/msg/String": "RIHS01_df668c740482bbd48fb39d76a70dfd4b"
    "d59db1288021743503259e948f6b1a18",
    "nav2_msgs/msg/SpeedLimit": "RIHS01_83d8e4e842559f4d9a988b19d31b1622"
    "16ec738536389f98438d1a166f91845a",
    "lifecycle_msgs/srv/ChangeState": "RIHS01_356fe34f0475a43acf54542013af4167"
    "b0e729f77ea22ffb045c6ad8e20668e5",
    "lifecycle_msgs/srv/GetState": "RIHS01_800a0a5aae599782b02932de0caf563f"
    "6dc4e7e94b794eadde075ba2cbef9795",
    "rcl_interfaces/srv/SetParameters": "RIHS01_56eed9a67e169f9cb6c1f987bc88f868"
    "c14a8fc9f743a263bc734c154015d7e0",
}
LABELS = {1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized"}
# transition id -> (from state, to state), lifecycle_msgs/msg/Transition
TRANSITIONS = {1: (1, 2), 2: (2, 1), 3: (2, 3), 4: (3, 2)}


def typestore() -> Any:
    """Return rosbags' Jazzy store with the few service and nav2 types it lacks."""
    store = get_typestore(Stores.ROS2_JAZZY)

    def body(text: str, pkg: str) -> Any:
        return next(iter(get_types_from_msg(text, f"{pkg}/msg/Body").values()))

    store.register(
        {
            "nav2_msgs/msg/SpeedLimit": body(
                "std_msgs/Header header\nbool percentage\nfloat64 speed_limit\n", "nav2_msgs"
            ),
            "lifecycle_msgs/srv/ChangeState_Request": body(
                "Transition transition\n", "lifecycle_msgs"
            ),
            "lifecycle_msgs/srv/ChangeState_Response": body("bool success\n", "lifecycle_msgs"),
            "lifecycle_msgs/srv/GetState_Request": body(
                "uint8 structure_needs_at_least_one_member\n", "lifecycle_msgs"
            ),
            "lifecycle_msgs/srv/GetState_Response": body("State current_state\n", "lifecycle_msgs"),
            "rcl_interfaces/srv/SetParameters_Request": body(
                "Parameter[] parameters\n", "rcl_interfaces"
            ),
            "rcl_interfaces/srv/SetParameters_Response": body(
                "SetParametersResult[] results\n", "rcl_interfaces"
            ),
        }
    )
    return store


def dds(ros_type: str) -> str:
    pkg, kind, name = ros_type.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


def attachment(seq: int, gid: bytes) -> bytes:
    """Return rmw_zenoh's attachment: int64 seq, int64 ns, LEB128 length 16, GID."""
    return struct.pack("<qqB", seq, time.time_ns(), 16) + gid


class Robot:
    """The stand-in robot; `run()` until `stop()`."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.store = typestore()
        self.ns = args.namespace.rstrip("/")
        self.percent = args.charge
        self.task = ""
        self.states = {name: 3 for name in args.managed}
        self.parameters: dict[str, float] = {}
        self.lock = threading.Lock()
        self.stopped = threading.Event()
        self.record = open(args.record, "a", encoding="utf-8") if args.record else None
        self.owned: list[Any] = []
        self.eid = 0

    def key(self, name: str, ros_type: str) -> str:
        return f"{self.args.domain}/{self.ns.strip('/')}/{name}/{dds(ros_type)}/{HASH[ros_type]}"

    def token(self, kind: str, node: str, name: str = "", ros_type: str = "") -> None:
        self.eid += 1
        ns = self.ns.replace("/", "%") or "%"
        key = f"@ros2_lv/{self.args.domain}/{self.zid}/{self.eid}/{self.eid}/{kind}/%/{ns}/{node}"
        if name:
            full = f"{self.ns}/{name}".replace("/", "%")
            key += f"/{full}/{dds(ros_type)}/{HASH[ros_type]}/::,10:,:,:,,"
        self.owned.append(self.session.liveliness().declare_token(key))

    def log(self, **entry: Any) -> None:
        if self.record is not None:
            with self.lock:
                self.record.write(json.dumps(entry) + "\n")
                self.record.flush()

    def open(self) -> None:
        conf = zenoh.Config()
        conf.insert_json5("mode", '"client"')
        conf.insert_json5("connect/endpoints", json.dumps([self.args.connect]))
        deadline = time.monotonic() + 30
        while True:
            try:
                self.session = zenoh.open(conf)
                break
            except zenoh.ZError:
                if time.monotonic() > deadline or self.stopped.is_set():
                    raise
                time.sleep(0.2)
        self.zid = str(self.session.zid())
        self.token("NN", "robot_driver")
        self.battery_pub = self.publisher("battery_state", "sensor_msgs/msg/BatteryState")
        self.diag_pub = self.publisher("diagnostics", "diagnostic_msgs/msg/DiagnosticArray")
        self.subscribe("speed_limit", "nav2_msgs/msg/SpeedLimit")
        self.subscribe("current_task", "std_msgs/msg/String")
        for name in self.args.managed:
            self.token("NN", name)
            self.serve(f"{name}/change_state", "lifecycle_msgs/srv/ChangeState", name)
            self.serve(f"{name}/get_state", "lifecycle_msgs/srv/GetState", name)
        self.token("NN", "controller_server")
        self.serve("controller_server/set_parameters", "rcl_interfaces/srv/SetParameters", "")

    def publisher(self, name: str, ros_type: str) -> list[Any]:
        self.token("MP", "robot_driver", name, ros_type)
        pub = self.session.declare_publisher(self.key(name, ros_type))
        self.owned.append(pub)
        return [pub, ros_type, 0, struct.pack("<Q", self.eid) * 2]

    def publish(self, pub: list[Any], message: Any) -> None:
        pub[2] += 1
        payload = bytes(self.store.serialize_cdr(message, pub[1]))
        pub[0].put(payload, attachment=attachment(pub[2], pub[3]))

    def subscribe(self, name: str, ros_type: str) -> None:
        self.token("MS", "robot_driver", name, ros_type)

        def on_sample(sample: zenoh.Sample) -> None:
            payload = sample.payload.to_bytes()
            att = sample.attachment.to_bytes() if sample.attachment is not None else b""
            message = self.store.deserialize_cdr(payload, ros_type)
            if ros_type == "std_msgs/msg/String":
                self.task = message.data
            self.log(topic=f"{self.ns}/{name}", type=ros_type, payload=payload.hex(),
                     attachment=att.hex(), key=str(sample.key_expr))  # fmt: skip

        self.owned.append(self.session.declare_subscriber(self.key(name, ros_type), on_sample))

    def serve(self, name: str, srv_type: str, device: str) -> None:
        self.token("SS", device or "controller_server", name, srv_type)

        def on_query(query: zenoh.Query) -> None:
            payload = query.payload.to_bytes() if query.payload is not None else b""
            att = query.attachment.to_bytes() if query.attachment is not None else b""
            request = self.store.deserialize_cdr(payload, f"{srv_type}_Request")
            response = self.answer(srv_type, device, request)
            seq, _, _ = struct.unpack_from("<qqB", att)
            reply = bytes(self.store.serialize_cdr(response, f"{srv_type}_Response"))
            query.reply(query.key_expr, reply, attachment=attachment(seq, att[17:33]))
            self.log(service=f"{self.ns}/{name}", type=srv_type, payload=payload.hex(),
                     attachment=att.hex(), key=str(query.key_expr))  # fmt: skip

        key = self.key(name, srv_type)
        self.owned.append(self.session.declare_queryable(key, on_query, complete=True))

    def answer(self, srv_type: str, device: str, request: Any) -> Any:
        types = self.store.types
        if srv_type == "lifecycle_msgs/srv/GetState":
            state = self.states[device]
            current = types["lifecycle_msgs/msg/State"](id=state, label=LABELS[state])
            return types["lifecycle_msgs/srv/GetState_Response"](current_state=current)
        if srv_type == "lifecycle_msgs/srv/ChangeState":
            before, after = TRANSITIONS.get(request.transition.id, (0, 0))
            ok = self.states[device] == before
            if ok:
                self.states[device] = after
            return types["lifecycle_msgs/srv/ChangeState_Response"](success=ok)
        results = []
        for parameter in request.parameters:
            self.parameters[parameter.name] = parameter.value.double_value
            result = types["rcl_interfaces/msg/SetParametersResult"]
            results.append(result(successful=True, reason=""))
        return types["rcl_interfaces/srv/SetParameters_Response"](results=results)

    def step(self, dt: float) -> None:
        charging = self.task == "Charging"
        rate = self.args.charge_rate if charging else -self.args.drain
        self.percent = min(100.0, max(0.0, self.percent + rate * dt))
        t = self.store.types
        stamp = t["builtin_interfaces/msg/Time"](sec=int(time.time()), nanosec=0)
        header = t["std_msgs/msg/Header"](stamp=stamp, frame_id="base_link")
        status = 4 if self.percent >= 100 else 1 if charging else 2
        self.publish(self.battery_pub, self.battery(header, status))
        statuses = []
        for name in [*self.args.unmanaged, *self.args.managed]:
            mode = "active" if name in self.args.unmanaged else LABELS[self.states[name]]
            kv = t["diagnostic_msgs/msg/KeyValue"]
            values = [kv(key="mode", value=mode)] if name in self.args.unmanaged else []
            values.append(kv(key="lifecycle", value=mode))
            level = 1 if name in self.args.warn else 0
            statuses.append(t["diagnostic_msgs/msg/DiagnosticStatus"](
                level=level, name=f"{self.ns.strip('/')}/{name}", message="OK", hardware_id=name,
                values=values))  # fmt: skip
        self.publish(self.diag_pub, t["diagnostic_msgs/msg/DiagnosticArray"](
            header=header, status=statuses))  # fmt: skip

    def battery(self, header: Any, status: int) -> Any:
        return self.store.types["sensor_msgs/msg/BatteryState"](
            header=header, voltage=24.0, temperature=30.0, current=-1.0, charge=float("nan"),
            capacity=float("nan"), design_capacity=20.0, percentage=self.percent / 100.0,
            power_supply_status=status, power_supply_health=1, power_supply_technology=2,
            present=True, cell_voltage=np.array([], dtype=np.float32),
            cell_temperature=np.array([], dtype=np.float32), location="base",
            serial_number="stand-in")  # fmt: skip

    def run(self) -> None:
        last = time.monotonic()
        while not self.stopped.wait(1.0 / self.args.rate):
            now = time.monotonic()
            self.step(now - last)
            last = now

    def close(self) -> None:
        while self.owned:
            self.owned.pop().undeclare()
        if hasattr(self, "session"):
            self.session.close()
        if self.record is not None:
            self.record.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--connect", default="tcp/127.0.0.1:7447")
    parser.add_argument("--domain", type=int, default=0)
    parser.add_argument("--namespace", default="/robot1")
    parser.add_argument("--charge", type=float, default=80.0, help="percent at start")
    parser.add_argument("--drain", type=float, default=0.0, help="percent lost a second")
    parser.add_argument("--charge-rate", type=float, default=5.0, help="percent gained a second")
    parser.add_argument("--rate", type=float, default=10.0, help="Hz of battery and diagnostics")
    parser.add_argument("--managed", nargs="*", default=["screen", "speakers", "microphone"])
    parser.add_argument("--unmanaged", nargs="*", default=["wheels", "laser", "base"])
    parser.add_argument("--warn", nargs="*", default=[], help="devices reported at level WARN")
    parser.add_argument("--record", type=Path, help="append what the robot receives (JSON lines)")
    args = parser.parse_args(argv)
    robot = Robot(args)
    signal.signal(signal.SIGTERM, lambda *_: robot.stopped.set())
    signal.signal(signal.SIGINT, lambda *_: robot.stopped.set())
    try:
        robot.open()
        print("ros2robot: up", flush=True)
        robot.run()
    finally:
        robot.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
