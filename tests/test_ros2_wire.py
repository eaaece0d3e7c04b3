"""rmw_zenoh's wire format as the bridge writes it: keys, tokens, attachments, CDR, hashes.

Where the expected RIHS01 values come from:

- std_msgs/msg/String `df668c74...` and example_interfaces/srv/AddTwoInts `e118de6b...`:
  the key examples in ros2/rmw_zenoh's docs/design.md ("Topic and Service name mapping").
- sensor_msgs/msg/BatteryState `4bee5dfc...`: `ros2 topic info -v` of a Jazzy robot
  ("Topic type hash: RIHS01_4bee5dfc...") and several independent ROS 2 client libraries.
- diagnostic_msgs/msg/DiagnosticArray, geometry_msgs/msg/PoseStamped, std_msgs/msg/Header,
  lifecycle_msgs/msg/State and /Transition, service_msgs/msg/ServiceEventInfo: a table of
  hashes generated from a Jazzy install by an independent C project (its service hashes
  disagree with design.md's AddTwoInts, so only its message hashes are used here).
- lifecycle_msgs ChangeState/GetState, rcl_interfaces SetParameters, nav2_msgs SpeedLimit: no
  published value was found; they are computed by the construction that reproduces
  design.md's AddTwoInts hash (test_the_service_hash_construction_matches_rmw_zenoh).
"""

from __future__ import annotations

import pytest
import zenoh.ext
from ros2robot import HASH

from agents.ros2.attachment import Attachment
from agents.ros2.codec import Codec, service_types
from agents.ros2.errors import MalformedAttachment, MalformedMessage, MalformedToken, MappingError
from agents.ros2.mapping import parse_mapping
from agents.ros2.rmw import Endpoint, Entity, EntityKind, Qos, data_key, mangle, parse_token

PUBLISHED = {
    "std_msgs/msg/String": ("df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"),
    "sensor_msgs/msg/BatteryState": (
        "4bee5dfce981c98faa6828b868307a0a73f992ed0789f374ee96c8f840e69741"
    ),
    "diagnostic_msgs/msg/DiagnosticArray": (
        "5a8a36efb05fb25070fa0fb3810290c0e6cd4862b54a8fb975a1ee8dc55a333e"
    ),
    "geometry_msgs/msg/PoseStamped": (
        "10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8"
    ),
    "std_msgs/msg/Header": ("f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01"),
    "lifecycle_msgs/msg/State": (
        "dd2d02b82f3ebc858e53c431b1e6e91f3ffc71436fc81d0715214ac6ee2107a0"
    ),
    "lifecycle_msgs/msg/Transition": (
        "c65d7b31ea134cba4f54fc867b817979be799f7452035cd35fac9b7421fb3424"
    ),
    "service_msgs/msg/ServiceEventInfo": (
        "41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45"
    ),
}
ADD_TWO_INTS = "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a"


@pytest.fixture(scope="module")
def codec() -> Codec:
    return Codec("jazzy")


@pytest.mark.parametrize("ros_type", sorted(PUBLISHED))
def test_type_hashes_equal_the_published_values(codec, ros_type):
    assert codec.type_hash(ros_type) == "RIHS01_" + PUBLISHED[ros_type]


def test_kilted_hashes_these_types_alike(codec):
    kilted = Codec("kilted")
    for ros_type in ("sensor_msgs/msg/BatteryState", "diagnostic_msgs/msg/DiagnosticArray"):
        assert kilted.type_hash(ros_type) == codec.type_hash(ros_type)


def test_the_service_hash_construction_matches_rmw_zenoh(tmp_path):
    srv = tmp_path / "example_interfaces" / "srv"
    srv.mkdir(parents=True)
    (srv / "AddTwoInts.srv").write_text("int64 a\nint64 b\n---\nint64 sum\n")
    assert Codec("jazzy", [tmp_path]).type_hash("example_interfaces/srv/AddTwoInts") == ADD_TWO_INTS


def test_the_stand_in_robot_and_the_bridge_agree_on_every_hash(codec):
    for ros_type, expected in HASH.items():
        assert codec.type_hash(ros_type) == expected, ros_type


def test_an_empty_request_gets_rosidls_placeholder_member():
    types = service_types("lifecycle_msgs/srv/GetState", "---\nState current_state\n")
    assert [f for f, _ in types["lifecycle_msgs/srv/GetState_Request"][1]] == [
        "structure_needs_at_least_one_member"
    ]


def test_data_keys_are_rmw_zenohs():
    assert (
        data_key(0, "/chatter", "std_msgs/msg/String", "RIHS01_x")
        == "0/chatter/std_msgs::msg::dds_::String_/RIHS01_x"
    )
    assert (
        data_key(2, "/robot1/screen/change_state", "lifecycle_msgs/srv/ChangeState", "RIHS01_y")
        == "2/robot1/screen/change_state/lifecycle_msgs::srv::dds_::ChangeState_/RIHS01_y"
    )


def test_tokens_mangle_names_and_round_trip():
    endpoint = Endpoint("/robot1/battery_state", "sensor_msgs/msg/BatteryState", "RIHS01_h", Qos())
    entity = Entity(0, "abc", 3, 7, EntityKind.SUBSCRIBER, "/robot1", "bridge", "", endpoint)
    token = entity.token()
    assert token == (
        "@ros2_lv/0/abc/3/7/MS/%/%robot1/bridge/%robot1%battery_state/"
        "sensor_msgs::msg::dds_::BatteryState_/RIHS01_h/::,10:,:,:,,"
    )
    assert parse_token(token) == entity
    node = Entity(5, "abc", 1, 1, EntityKind.NODE, "/", "talker")
    assert node.token() == "@ros2_lv/5/abc/1/1/NN/%/%/talker"
    assert parse_token(node.token()) == node
    assert mangle("") == "%"


def test_qos_strings_leave_defaults_empty():
    assert Qos().encode() == "::,10:,:,:,,"
    assert Qos(transient_local=True, depth=1).encode() == ":1:,1:,:,:,,"
    assert Qos(reliable=False, keep_all=True).encode() == "2::2,:,:,:,,"
    for qos in (Qos(), Qos(transient_local=True, depth=1), Qos(reliable=False, depth=5)):
        assert Qos.decode(qos.encode()) == qos


@pytest.mark.parametrize(
    "key",
    [
        "@ros2_lv/0/abc/1/1/XX/%/%/n",
        "@ros2_lv/zero/abc/1/1/NN/%/%/n",
        "@ros2_lv/0/abc/1/2/MP/%/%/n/%t/std_msgs::msg::dds_::String_/RIHS01_h",
        "@ros2_lv/0/abc/1/2/MP/%/%/n/%t/std_msgs/String/RIHS01_h/::,10:,:,:,,",
        "other/0/abc/1/1/NN/%/%/n",
    ],
)
def test_malformed_tokens_are_named(key):
    with pytest.raises(MalformedToken):
        parse_token(key)


def test_the_attachment_is_what_zenoh_ext_serializes():
    gid = bytes(range(16))
    ours = Attachment(42, 1_700_000_000_123_456_789, gid).encode()
    ext = zenoh.ext.z_serialize(
        (zenoh.ext.Int64(42), zenoh.ext.Int64(1_700_000_000_123_456_789), gid)
    ).to_bytes()
    assert ours == ext and len(ours) == 33
    assert Attachment.decode(ours) == Attachment(42, 1_700_000_000_123_456_789, gid)
    with pytest.raises(MalformedAttachment):
        Attachment.decode(ours[:-1])
    with pytest.raises(MalformedAttachment):
        Attachment.decode(ours[:16] + b"\x0f" + gid)


def test_cdr_round_trips_and_malformed_payloads_are_named(codec):
    message = codec.new("sensor_msgs/msg/BatteryState", percentage=0.5, power_supply_status=2)
    payload = codec.encode("sensor_msgs/msg/BatteryState", message)
    assert payload[:4] == b"\x00\x01\x00\x00"  # CDR little endian encapsulation
    assert codec.decode("sensor_msgs/msg/BatteryState", payload).percentage == 0.5
    for bad in (payload[:20], b"", b"\x07\x07\x00\x00abcd", payload[:4]):
        with pytest.raises(MalformedMessage):
            codec.decode("sensor_msgs/msg/BatteryState", bad)


def test_mapping_errors_say_where():
    with pytest.raises(MappingError, match=r"line 1, column"):
        parse_mapping("[[battery]\n", "robot1")
    with pytest.raises(MappingError, match=r"unknown tables \['batery'\]"):
        parse_mapping("[[batery]]\ntopic='x'\n", "robot1")
    with pytest.raises(MappingError, match=r"\[\[lifecycle\]\] #1: unknown keys \['nodes'\]"):
        parse_mapping("[[lifecycle]]\nnodes='x'\n", "robot1")
    with pytest.raises(MappingError, match=r"not a valid ROS name"):
        parse_mapping("[[task]]\ntopic='bad topic'\n", "robot1")
    mapping = parse_mapping("[ros]\ndomain=3\n[[task]]\ntopic='task'\n", "robot2")
    assert mapping.domain == 3 and mapping.tasks == ("/robot2/task",)
