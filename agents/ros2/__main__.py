"""`python -m agents.ros2`: run the ROS 2 bridge for one robot (see `--help`)."""

from __future__ import annotations

import sys

from agents.base import run_agent
from agents.ros2.bridge import Ros2Bridge


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the ROS 2 bridge (see `--help`; `prog` names the command in its usage line)."""
    return run_agent(Ros2Bridge, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
