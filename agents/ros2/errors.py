"""Errors of the ROS 2 bridge, named for what went wrong."""

from __future__ import annotations

from space import InputError, MalformedPayload, SpaceError


class MappingError(InputError):
    """A mapping file is missing, not TOML, or does not have the expected shape."""


class UnknownRosType(SpaceError):
    """A ROS type is neither in the type store nor in the shipped definitions."""


class MalformedMessage(MalformedPayload):
    """A CDR payload could not be decoded as the type its key names."""


class MalformedAttachment(MalformedPayload):
    """A sample's attachment is not the 33 bytes rmw_zenoh writes."""


class MalformedToken(MalformedPayload):
    """A liveliness key is not an rmw_zenoh token."""


class ServiceTimeout(SpaceError):
    """A ROS 2 service did not answer in time (no server, or it is busy)."""


class ServiceFailed(SpaceError):
    """A ROS 2 service answered with an error reply."""
