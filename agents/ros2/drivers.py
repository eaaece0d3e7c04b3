"""Service-driven actuators: a managed node's lifecycle, a controller's parameter.

Service calls block (a Zenoh get waits for the server's answer), so each
driver runs them on its own thread and only the latest wish counts: a running
mode that flips twice while a transition is under way costs one more
transition, not two. What the robot answers (or that it did not) is handed to
`report`, which must not block (the bridge passes it to its loop).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

from agents.ros2.errors import ServiceFailed, ServiceTimeout
from agents.ros2.node import Client, Node
from space import MalformedPayload

log = logging.getLogger("ros2.drivers")
RETRY = 2.0
POLL = 5.0

# lifecycle_msgs/msg/State primary states and lifecycle_msgs/msg/Transition ids
UNCONFIGURED, INACTIVE, ACTIVE, FINALIZED = 1, 2, 3, 4
CONFIGURE, CLEANUP, ACTIVATE, DEACTIVATE = 1, 2, 3, 4
_NEXT = {
    (UNCONFIGURED, INACTIVE): CONFIGURE,
    (UNCONFIGURED, ACTIVE): CONFIGURE,
    (INACTIVE, ACTIVE): ACTIVATE,
    (INACTIVE, UNCONFIGURED): CLEANUP,
    (ACTIVE, INACTIVE): DEACTIVATE,
    (ACTIVE, UNCONFIGURED): DEACTIVATE,
}


def next_transition(current: int, target: int) -> int | None:
    """Return the transition that brings a node in `current` closer to `target`, or None."""
    return _NEXT.get((current, target))


class LatestWins:
    """A thread that works toward the latest wish, retrying every `RETRY` s until it gets there.

    Subclasses implement `reach(wish)`, returning True once the wish holds.
    """

    name = "driver"
    idle: float | None = None  # once reached, act again after this many seconds (None: never)

    def __init__(self) -> None:
        self._wish: Any = None
        self._dirty = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Start the thread."""
        self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
        self._thread.start()

    def want(self, wish: Any) -> None:
        """Make `wish` the one to reach; returns at once, from any thread."""
        self._wish = wish
        self._dirty.set()

    def close(self) -> None:
        """Stop the thread (a call under way finishes, up to its timeout)."""
        self._stop.set()
        self._dirty.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None

    def _run(self) -> None:
        reached = True
        while True:
            self._dirty.wait(self.idle if reached else RETRY)
            if self._stop.is_set():
                return
            self._dirty.clear()
            try:
                reached = self.reach(self._wish)
            except (ServiceTimeout, ServiceFailed, MalformedPayload) as exc:
                reached = self.failed(exc)
            except Exception:  # the thread must outlive one bad answer; logged, retried
                log.exception("%s failed; retrying", self.name)
                reached = False

    def reach(self, wish: Any) -> bool:
        """Act toward `wish`; return True once it holds (False retries after `RETRY` s)."""
        raise NotImplementedError

    def failed(self, exc: Exception) -> bool:
        """Report a call that failed; return True to stop retrying."""
        raise NotImplementedError


class ManagedNode(LatestWins):
    """Drive one lifecycle node toward a primary state; report the state it says it is in.

    The node is asked again every `POLL` s once there: a state changed behind the
    bridge's back (`ros2 lifecycle set`, a node restarted) is reported, and led
    back to the commanded one.

    Args:
        bridge: the bridge's ROS node, which declares the clients.
        node: the managed node's fully qualified name (`/robot1/screen`).
        timeout: seconds each service call may take.
        report: `report(state_id, None)` with the node's state, or
            `report(None, reason)` when it did not answer.
    """

    def __init__(
        self,
        bridge: Node,
        node: str,
        timeout: float,
        report: Callable[[int | None, str | None], None],
    ) -> None:
        super().__init__()
        self.name, self.idle = f"lifecycle {node}", POLL
        self.node, self.timeout, self.report = node, timeout, report
        self._codec = bridge.codec
        self._change: Client = bridge.client(
            f"{node}/change_state", "lifecycle_msgs/srv/ChangeState"
        )
        self._get: Client = bridge.client(f"{node}/get_state", "lifecycle_msgs/srv/GetState")

    def state(self) -> int:
        """Ask the node its primary state (blocking)."""
        request = self._codec.new("lifecycle_msgs/srv/GetState_Request")
        return int(self._get.call(request, self.timeout).current_state.id)

    def reach(self, wish: Any) -> bool:
        """Take the transitions from the node's state to `wish` (None: only ask), one by one."""
        current = self.state()
        for _ in range(len(_NEXT)):  # a node that says "done" but stays put is not asked forever
            transition = None if wish is None else next_transition(current, wish)
            if transition is None:
                break
            request = self._codec.new(
                "lifecycle_msgs/srv/ChangeState_Request", transition={"id": transition}
            )
            answer = self._change.call(request, self.timeout)
            log.info(
                "%s: transition %d %s",
                self.node,
                transition,
                "done" if answer.success else "refused",
            )
            current = self.state()
            if not answer.success:
                break
        self.report(current, None)
        return wish is None or current == wish or current == FINALIZED

    def failed(self, exc: Exception) -> bool:
        """Report that the node did not answer; keep retrying."""
        self.report(None, str(exc))
        return False


class Parameter(LatestWins):
    """Set one double parameter of a node through `rcl_interfaces/srv/SetParameters`.

    Args:
        bridge: the bridge's ROS node.
        node: the node owning the parameter (`/robot1/controller_server`).
        name: the parameter (`FollowPath.max_vel_x`).
        timeout: seconds the call may take.
        report: `report(True, reason)` when set, `(False, reason)` when refused or unanswered.
    """

    def __init__(
        self,
        bridge: Node,
        node: str,
        name: str,
        timeout: float,
        report: Callable[[bool, str], None],
    ) -> None:
        super().__init__()
        self.name = f"parameter {node} {name}"
        self.node, self.parameter, self.timeout, self.report = node, name, timeout, report
        self._codec = bridge.codec
        self._set = bridge.client(f"{node}/set_parameters", "rcl_interfaces/srv/SetParameters")

    def reach(self, wish: Any) -> bool:
        """Set the parameter to `wish` (a float); True once the node took it."""
        if wish is None:
            return True
        value = {"type": 3, "double_value": float(wish)}  # ParameterType.PARAMETER_DOUBLE
        request = self._codec.new(
            "rcl_interfaces/srv/SetParameters_Request",
            parameters=[
                self._codec.new("rcl_interfaces/msg/Parameter", name=self.parameter, value=value)
            ],
        )
        results = self._set.call(request, self.timeout).results
        ok = bool(results) and bool(results[0].successful)
        self.report(ok, results[0].reason if results else "no result")
        return True

    def failed(self, exc: Exception) -> bool:
        """Report that the node did not answer; keep retrying."""
        self.report(False, str(exc))
        return False
