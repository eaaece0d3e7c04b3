"""The ROS 2 bridge: robots on rmw_zenoh take part in the space, with no ROS installed.

`python -m agents.ros2` (or `tspace agent ros2`) runs it; docs/ros2.md says how.
"""

from agents.ros2.attachment import Attachment
from agents.ros2.codec import Codec
from agents.ros2.rmw import Endpoint, Entity, EntityKind, Qos, data_key, parse_token

__all__ = [
    "Attachment",
    "Codec",
    "Endpoint",
    "Entity",
    "EntityKind",
    "Qos",
    "data_key",
    "parse_token",
]
