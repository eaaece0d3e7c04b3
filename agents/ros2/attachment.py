"""The attachment rmw_zenoh puts on every message, request and reply.

Since rmw_zenoh 0.2.4 (Jazzy), in Kilted and Rolling, it is what zenoh-ext's
serializer writes for (int64 sequence number, int64 source timestamp in ns,
16 bytes of source GID): two little-endian int64, then the GID as a sequence,
its length (16) as a one-byte LEB128, then the bytes. 33 bytes in all.
"""

from __future__ import annotations

import hashlib
import struct
import time
from dataclasses import dataclass

from agents.ros2.errors import MalformedAttachment

GID_SIZE = 16
SIZE = 8 + 8 + 1 + GID_SIZE
_HEAD = struct.Struct("<qqB")


def gid_for(token: str) -> bytes:
    """Return a stable 16-byte GID for the entity a liveliness token names."""
    return hashlib.sha256(token.encode()).digest()[:GID_SIZE]


@dataclass(frozen=True)
class Attachment:
    """Sequence number, source time and writer of one sample.

    Attributes:
        sequence: the writer's sequence number (a request's matches its reply).
        timestamp: source time in nanoseconds since the epoch.
        gid: the writer's (or the requesting client's) 16-byte GID.
    """

    sequence: int
    timestamp: int
    gid: bytes

    @classmethod
    def now(cls, sequence: int, gid: bytes) -> Attachment:
        """Return an attachment stamped with the current time."""
        return cls(sequence, time.time_ns(), gid)

    def encode(self) -> bytes:
        """Return the 33 bytes rmw_zenoh expects."""
        return _HEAD.pack(self.sequence, self.timestamp, GID_SIZE) + self.gid

    @classmethod
    def decode(cls, data: bytes) -> Attachment:
        """Parse an attachment.

        Raises:
            MalformedAttachment: not 33 bytes, or the GID length is not 16.
        """
        if len(data) != SIZE:
            raise MalformedAttachment(f"attachment of {len(data)} bytes, expected {SIZE}")
        sequence, timestamp, length = _HEAD.unpack_from(data)
        if length != GID_SIZE:
            raise MalformedAttachment(f"attachment GID length {length}, expected {GID_SIZE}")
        return cls(sequence, timestamp, bytes(data[_HEAD.size :]))
