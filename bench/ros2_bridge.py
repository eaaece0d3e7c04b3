"""What the ROS 2 bridge costs: message in -> triple in the space, and CPU at 20 topics x 100 Hz.

Latency: a BatteryState put on the robot's key (as an rmw_zenoh publisher would)
until a subscriber of the space sees the new `ac:charge_percent`; side by side
with the same triple written straight into the space (the path without the
bridge). CPU: 10 BatteryState and 10 PoseStamped topics at 100 Hz each for
`--seconds`, the bridge's user+system time from /proc over wall time.

    python bench/ros2_bridge.py [--runs 5] [--count 200] [--seconds 10]
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from _harness import median, percentile, serve
from _output import OUT, bench_parser, parse, print_table
from rdflib import Graph, Literal, Namespace

from agents.ros2.codec import Codec
from agents.ros2.rmw import data_key
from space import TripleSpace

REPO = Path(__file__).resolve().parents[1]
AC = Namespace("https://w3id.org/tspace/selfconfig#")
TOPICS = 10  # of each kind: 10 battery + 10 pose = 20
SENT = [0]  # every ROS message put, to compare with what the bridge says it received


def mapping_text() -> str:
    lines = ['[ros]\nmax_rate = 5.0\n', '[[battery]]\ntopic = "battery_state"\n'
             'device = "{robot}_battery"\nmax_rate = 100000.0\n']  # fmt: skip
    for i in range(TOPICS):
        lines.append(f'[[battery]]\ntopic = "battery_{i}"\ndevice = "{{robot}}_battery_{i}"\n')
        lines.append(f'[[pose]]\ntopic = "pose_{i}"\n')
    return "\n".join(lines)


def start_bridge(endpoint: str, space: str, mapping: Path, log: Path) -> subprocess.Popen:
    argv = [sys.executable, "-m", "agents.ros2", "--connect", endpoint, "--space", space,
            "--mapping", str(mapping), "--tick", "0.05"]  # fmt: skip
    with open(log, "wb") as out:
        return subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT, cwd=REPO)


def wait_ready(log: Path, proc: subprocess.Popen) -> None:
    deadline = time.monotonic() + 30
    while "ROS 2 node" not in log.read_text(errors="replace"):
        if proc.poll() is not None or time.monotonic() > deadline:
            raise RuntimeError(f"bridge did not start:\n{log.read_text(errors='replace')}")
        time.sleep(0.05)


def battery_payload(codec: Codec, fraction: float) -> bytes:
    msg = codec.new("sensor_msgs/msg/BatteryState", percentage=fraction, power_supply_status=2)
    return codec.encode("sensor_msgs/msg/BatteryState", msg)


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def latency(ts: TripleSpace, codec: Codec, count: int, direct: bool) -> list[float]:
    """Return ms from put (or write) to notification of a changed charge, `count` times."""
    seen = threading.Event()
    expected: list[Literal] = [Literal(0)]

    def on_change(change) -> None:
        if any(o == expected[0] for _, _, o in change.added):
            seen.set()

    key = data_key(0, "/robot1/battery_state", "sensor_msgs/msg/BatteryState",
                   codec.type_hash("sensor_msgs/msg/BatteryState"))  # fmt: skip
    payloads = {30: battery_payload(codec, 0.32), 60: battery_payload(codec, 0.62)}
    sub = ts.subscribe((AC.robot1_battery, AC.charge_percent, None), on_change)
    delays = []
    try:
        for i in range(count + 10):
            charge = 30 if i % 2 else 60
            expected[0] = Literal(charge)
            seen.clear()
            start = time.perf_counter()
            if direct:
                battery = AC.robot1_battery
                ts.apply([(battery, AC.charge_percent, Literal(charge))],
                         [(battery, AC.charge_percent, Literal(90 - charge))])  # fmt: skip
            else:
                ts.session.put(key, payloads[charge])
            if not seen.wait(5):
                raise RuntimeError(f"no notification for charge {charge}")
            if i >= 10:  # warm-up
                delays.append((time.perf_counter() - start) * 1000)
    finally:
        sub.close()
    return delays


def load(ts: TripleSpace, codec: Codec, pid: int, seconds: float) -> tuple[float, float, int]:
    """Publish 20 topics at 100 Hz; return (bridge cores, achieved Hz per topic, writes seen)."""
    hash_b = codec.type_hash("sensor_msgs/msg/BatteryState")
    hash_p = codec.type_hash("geometry_msgs/msg/PoseStamped")
    pubs = [ts.session.declare_publisher(
        data_key(0, f"/robot1/battery_{i}", "sensor_msgs/msg/BatteryState", hash_b))
        for i in range(TOPICS)] + [ts.session.declare_publisher(
        data_key(0, f"/robot1/pose_{i}", "geometry_msgs/msg/PoseStamped", hash_p))
        for i in range(TOPICS)]  # fmt: skip
    batteries = [battery_payload(codec, f / 100) for f in range(101)]
    poses = [codec.encode("geometry_msgs/msg/PoseStamped", codec.new(
        "geometry_msgs/msg/PoseStamped", pose={"position": {"x": k * 0.01, "y": 1.0}}))
        for k in range(1000)]  # fmt: skip
    writes = [0]
    sub = ts.subscribe(
        (None, AC.charge_percent, None), lambda c: writes.__setitem__(0, writes[0] + 1)
    )
    sub2 = ts.subscribe(
        (AC.robot1, AC.position_x, None), lambda c: writes.__setitem__(0, writes[0] + 1)
    )
    sent, cpu0, wall0 = 0, cpu_seconds(pid), time.monotonic()
    try:
        tick = 0
        while time.monotonic() - wall0 < seconds:
            for i, pub in enumerate(pubs):
                if i < TOPICS:
                    pub.put(batteries[(tick // 50 + i) % 101])  # a new 1 % step every 0.5 s
                else:
                    pub.put(poses[tick % 1000])  # moving: every message differs
            sent += len(pubs)
            SENT[0] += len(pubs)
            tick += 1
            time.sleep(max(0.0, wall0 + tick * 0.01 - time.monotonic()))
        wall = time.monotonic() - wall0
        cores = (cpu_seconds(pid) - cpu0) / wall
    finally:
        sub.close()
        sub2.close()
        for pub in pubs:
            pub.undeclare()
    return cores, sent / len(pubs) / wall, writes[0]


def main() -> None:
    parser = bench_parser(__doc__)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parse(parser)
    codec = Codec()
    knowledge = Graph()
    knowledge.parse(REPO / "ontology" / "selfconfig.ttl")
    knowledge.parse(REPO / "ontology" / "robots" / "hospital.ttl")
    rows = []
    with serve() as endpoint, tempfile.TemporaryDirectory() as tmp:
        mapping, log = Path(tmp) / "mapping.toml", Path(tmp) / "bridge.log"
        mapping.write_text(mapping_text())
        with TripleSpace.open(endpoint, space="bench") as ts:
            ts.write(knowledge, timeout=10)
            bridge = start_bridge(endpoint, "bench", mapping, log)
            try:
                wait_ready(log, bridge)
                p50s = {True: [], False: []}
                p99s = {True: [], False: []}
                for _ in range(args.runs):
                    for direct in (True, False):
                        delays = latency(ts, codec, args.count, direct)
                        p50s[direct].append(percentile(delays, 50))
                        p99s[direct].append(percentile(delays, 99))
                loads = [load(ts, codec, bridge.pid, args.seconds) for _ in range(3)]
                SENT[0] += (args.count + 10) * args.runs
            finally:
                bridge.terminate()
                bridge.wait(timeout=15)
        said = [line for line in log.read_text().splitlines() if "received" in line]
        print(f"messages put: {SENT[0]}; the bridge: {said[-1] if said else '?'}", flush=True)
    rows.append(["space write -> notified (no bridge), p50 ms", median(p50s[True]), *p50s[True]])
    rows.append(["ROS put -> triple notified, p50 ms", median(p50s[False]), *p50s[False]])
    rows.append(["space write -> notified (no bridge), p99 ms", median(p99s[True]), *p99s[True]])
    rows.append(["ROS put -> triple notified, p99 ms", median(p99s[False]), *p99s[False]])
    rows.append(["20 topics: bridge CPU, cores", median([c for c, _, _ in loads]),
                 *[c for c, _, _ in loads]])  # fmt: skip
    rows.append(["20 topics: Hz per topic sent", median([h for _, h, _ in loads]),
                 *[h for _, h, _ in loads]])  # fmt: skip
    rows.append(["20 topics: writes into the space", median([float(w) for *_, w in loads]),
                 *[float(w) for *_, w in loads]])  # fmt: skip
    width = max(len(r) for r in rows)
    rows = [r + [""] * (width - len(r)) for r in rows]
    header = ["measure", "median", *[f"run {i + 1}" for i in range(width - 2)]]
    text = print_table(f"ros2_bridge ({args.runs} latency runs of {args.count}, "
                       f"3 load runs of {args.seconds:g} s)", header, rows)  # fmt: skip
    OUT.mkdir(exist_ok=True)
    (OUT / "ros2_bridge.txt").write_text(text + "\n")


if __name__ == "__main__":
    main()
