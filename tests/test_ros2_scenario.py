"""The paper's battery example on a ROS 2 robot: `tspace up deploy/hospital-ros2.toml`.

The hospital robot's devices are the stand-in rmw_zenoh robot's (tests/ros2robot.py),
reached only through the bridge: its battery drains and charges on its own, and its
interaction devices are managed nodes the bridge drives through lifecycle transitions.
"""

from __future__ import annotations

from ros2robot import typestore
from test_ros2_bridge import StandIn
from test_scenario_battery import STEPS, completed_steps, needs_reasoner
from uprun import Up

from conftest import REPO, wait_for

LAUNCH = REPO / "deploy" / "hospital-ros2.toml"
INTERACTION = ("screen", "speakers", "microphone")


@needs_reasoner
def test_the_battery_scenario_runs_on_a_ros2_robot(tmp_path):
    with Up(tmp_path, LAUNCH, "--scenario", "battery", "--once") as up:
        robot = StandIn(
            f"tcp/127.0.0.1:{up.port}", tmp_path, "--charge", "13", "--drain", "0.3",
            "--charge-rate", "5", "--rate", "10",
        )  # fmt: skip
        try:
            status = up.proc.wait(timeout=9 * 90)
            explain = up.logs() + "\n--- robot\n" + robot.log.read_text(errors="replace")
            assert status == 0, explain
            wait_for(lambda: up.stdout_has("scenario battery: completed"), 5, "the last line")
        finally:
            robot.close()
    assert completed_steps(up) == STEPS, explain
    # The devices were switched by their nodes' lifecycle: deactivate (4) on each
    # interaction node, answered by the robot, and the mode written back is the
    # node's (the bridge's log shows the transition done, then the state it read).
    store = typestore()
    changes = [
        (r["service"], store.deserialize_cdr(
            bytes.fromhex(r["payload"]), "lifecycle_msgs/srv/ChangeState_Request"
        ).transition.id)
        for r in robot.received()
        if r.get("service", "").endswith("/change_state")
    ]  # fmt: skip
    for name in INTERACTION:
        assert (f"/robot1/{name}/change_state", 4) in changes, changes
    bridge_log = (up.data / "logs" / "ros2.log").read_text()
    for name in INTERACTION:
        assert f"/robot1/{name}: transition 4 done" in bridge_log
    # The battery the space saw was the robot's: very low, then charged on the dock.
    topics = {r.get("topic") for r in robot.received()}
    assert {"/robot1/speed_limit", "/robot1/current_task"} <= topics
