"""Hardware TCPROS programs and their RTL engines, against rosbags' ROS 1 serialization and by hand."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from hetros import HardwareError
from hetros.hw.designs._tcpros import Ros1Deframer, Ros1Framer, ros1_program, run_program
from hetros.hw.nodes import NodeUnderTest
from hetros.hw.sim._sim import simulate
from hetros.msg import registry
from hetros.transport.tcpros import Ros1Type
from tests.support.messages import cdr_body

TYPES = registry()


def _body(typename: str, message: Any) -> bytes:
    return cdr_body(TYPES, typename, message)


def _messages() -> dict[str, list[Any]]:
    string, image = TYPES.get("std_msgs/msg/String"), TYPES.get("sensor_msgs/msg/Image")
    scan, point = TYPES.get("sensor_msgs/msg/LaserScan"), TYPES.get("geometry_msgs/msg/Point")
    camera = image(height=3, width=5, encoding="mono8", step=5, data=np.arange(15, dtype=np.uint8))
    camera.header.frame_id = "cam"
    ranges = scan(angle_min=0.5, ranges=np.array([1, 2, 3], np.float32), intensities=np.array([], np.float32))
    ranges.header.frame_id = "x"
    return {"std_msgs/msg/String": [string(data="hello world 7"), string(data=""), string(data="a")],
            "sensor_msgs/msg/Image": [camera, image()], "sensor_msgs/msg/LaserScan": [ranges],
            "geometry_msgs/msg/Point": [point(x=1.0), point(z=2.0)],
            "std_msgs/msg/Empty": [TYPES.get("std_msgs/msg/Empty")()],
            "sensor_msgs/msg/Imu": [TYPES.get("sensor_msgs/msg/Imu")()],
            "sensor_msgs/msg/NavSatFix": [_fix("gps"), _fix("")]}


def _fix(frame_id: str) -> Any:
    """A NavSatFix: its only variable field (``frame_id``) comes first, 100 fixed bytes after it."""
    fix = TYPES.get("sensor_msgs/msg/NavSatFix")(latitude=52.5, longitude=13.4, altitude=34.0,
                                                 position_covariance=np.arange(9, dtype=np.float64))
    fix.header.frame_id = frame_id
    fix.status.status = 2
    return fix


@pytest.mark.parametrize("typename", sorted(_messages()))
def test_the_reference_program_makes_rosbags_ros1_bytes_and_back(typename: str) -> None:
    program = ros1_program(TYPES, typename)
    for message in _messages()[typename]:
        body = _body(typename, message)
        frame = run_program(program, body, to_ros1=True)
        ros1 = bytes(Ros1Type(TYPES, typename).serialize(message))
        assert frame == len(ros1).to_bytes(4, "little") + ros1
        assert run_program(program, frame, to_ros1=False) == body


def test_a_header_frame_by_hand() -> None:
    """PointStamped: ROS 1 adds Header.seq, drops the NUL of frame_id and CDR's padding before x."""
    point = TYPES.get("geometry_msgs/msg/PointStamped")()
    point.header.stamp.sec, point.header.stamp.nanosec = 1, 2
    point.header.frame_id = "ab"
    point.point.x = 1.0
    frame = run_program(ros1_program(TYPES, "geometry_msgs/msg/PointStamped"), _body(
        "geometry_msgs/msg/PointStamped", point), to_ros1=True)
    expected = bytes.fromhex(
        "2a000000"           # the frame's length: 42
        "00000000"           # header.seq (ROS 1 only)
        "01000000 02000000"  # stamp sec, nsec
        "02000000 6162"      # frame_id: 2 bytes, no NUL
        "000000000000f03f"   # x, right after (CDR pads 5 bytes here)
        "0000000000000000 0000000000000000".replace(" ", ""))
    assert frame == expected


@pytest.mark.parametrize("typename, field", [("sensor_msgs/msg/JointState", "name"),
                                             ("std_msgs/msg/Float64MultiArray", "layout.dim")])
def test_sequences_of_strings_or_messages_are_refused_naming_the_field(typename: str, field: str) -> None:
    with pytest.raises(HardwareError, match=rf"{typename}\.{field} is a sequence of .*leave it to the ROS 1 bridge"):
        ros1_program(TYPES, typename)


def test_bytes_that_do_not_fit_the_type_are_refused_with_the_offset() -> None:
    program = ros1_program(TYPES, "std_msgs/msg/String")
    with pytest.raises(HardwareError, match="needs 9 bytes at offset 4, the message ends at 8"):
        run_program(program, bytes.fromhex("0a00000068656c6c"), to_ros1=True)
    with pytest.raises(HardwareError, match="starts with its length"):
        run_program(program, bytes.fromhex("0900000001000000"), to_ros1=False)


@pytest.mark.parametrize("typename", sorted(_messages()))
@pytest.mark.parametrize("data_width", [8, 64])
def test_the_rtl_framer_and_deframer_match_the_reference(typename: str, data_width: int) -> None:
    """Back-pressure and idle cycles at random; messages back to back."""
    program = ros1_program(TYPES, typename)
    bodies = [_body(typename, m) for m in _messages()[typename]]
    frames = [run_program(program, b, to_ros1=True) for b in bodies]
    framed = simulate(NodeUnderTest(Ros1Framer(program, data_width, 1024), ["cdr"], ["frame"], data_width),
                      [bodies], idle=0.3, stall=0.3, seed=1, max_cycles=50_000)
    assert framed.received[0] == frames
    read = simulate(NodeUnderTest(Ros1Deframer(program, data_width), ["frame"], ["cdr"], data_width),
                    [frames], idle=0.3, stall=0.3, seed=2, max_cycles=50_000)
    assert read.received[0] == bodies


def test_a_large_image_streams_with_only_its_header_held() -> None:
    """The framer holds the ROS 1 bytes before ``data`` (a header, a few dozen bytes), then streams: a
    5,000-pixel image frames through a 64-byte store. A frame whose held part is longer than the store
    is dropped (reported by the engine's ``malformed``), and the next one goes through."""
    typename = "sensor_msgs/msg/Image"
    program = ros1_program(TYPES, typename)
    image = TYPES.get(typename)
    pixels = np.random.default_rng(3).integers(0, 256, 5000, dtype=np.uint8)
    large = image(height=50, width=100, encoding="mono8", step=100, data=pixels)
    large.header.frame_id = "camera"
    too_long = image(height=1, width=3, encoding="mono8", step=3, data=np.arange(3, dtype=np.uint8))
    too_long.header.frame_id = "f" * 80
    bodies = [_body(typename, m) for m in (large, too_long, large)]
    framed = simulate(NodeUnderTest(Ros1Framer(program, 64, 64), ["cdr"], ["frame"], 64), [bodies[:1]],
                      stall=0.2, seed=4, max_cycles=200_000)
    assert framed.received[0] == [run_program(program, bodies[0], to_ros1=True)]
    with pytest.raises(HardwareError, match="moved 2 of 3 messages"):  # the middle one never comes out
        simulate(NodeUnderTest(Ros1Framer(program, 64, 64), ["cdr"], ["frame"], 64), [bodies], seed=4,
                 max_cycles=60_000)
