"""hetros types as ROS 1 knows them: md5sums, definitions, the field mapping, services."""

from __future__ import annotations

import hashlib
import random

import numpy as np
import pytest

from hetros import SerializationError, UnknownTypeError
from hetros.msg import TypeRegistry
from hetros.transport.tcpros import Ros1Type
from hetros.transport.tcpros._types import SPLICE_MIN, Ros1ServiceType, md5_text, ros1_store
from tests.support.messages import random_message

TYPES = TypeRegistry()


def test_md5_text_gives_rosbags_md5_for_every_ros1_type() -> None:
    store = ros1_store()
    for name in store.fielddefs:
        assert hashlib.md5(md5_text(store, name).encode()).hexdigest() == store.generate_msgdef(
            name, ros_version=1)[1], name


@pytest.mark.parametrize(("typename", "md5"), [
    ("std_msgs/msg/String", "992ce8a1687cec8c8bd883ec73ca41d1"),
    ("sensor_msgs/msg/Image", "060021388200f6f0f447d0fcd9c64743"),
    ("sensor_msgs/msg/CameraInfo", "c9a58c1b0b154e0e6da7578cb991d214"),
    ("geometry_msgs/msg/Twist", "9f195f881246fdfa2798d1d3eebca84a"),
])
def test_message_md5s_are_stock_ros1s(typename: str, md5: str) -> None:
    assert Ros1Type(TYPES, typename).md5 == md5


@pytest.mark.parametrize(("service", "md5"), [
    ("std_srvs/srv/SetBool", "09fb03525b03e7ea1fd3992bafd87e16"),
    ("std_srvs/srv/Trigger", "937c9679a518e3a18d831e57125ea522"),
    ("std_srvs/srv/Empty", "d41d8cd98f00b204e9800998ecf8427e"),
    ("example_interfaces/srv/AddTwoInts", "6a2e34150c00229791cc89ff309fff21"),
])
def test_service_md5s_are_stock_ros1s(service: str, md5: str) -> None:
    kind = Ros1ServiceType(TYPES, service)
    assert kind.md5 == md5
    request = TYPES.get_service(service).Request()
    assert kind.request.deserialize(kind.request.serialize(request)) == request


def test_header_seq_is_zero_going_out_and_dropped_coming_in() -> None:
    kind = Ros1Type(TYPES, "std_msgs/msg/Header")
    header = TYPES.get("std_msgs/msg/Header")(frame_id="map")
    header.stamp.sec, header.stamp.nanosec = 3, 4
    data = kind.serialize(header)
    assert data[:12] == bytes(4) + (3).to_bytes(4, "little") + (4).to_bytes(4, "little")  # seq, secs, nsecs
    assert kind.deserialize(data) == header


def test_lower_cased_ros2_fields_map_to_ros1s_upper_case() -> None:
    kind = Ros1Type(TYPES, "sensor_msgs/msg/CameraInfo")
    info = TYPES.get("sensor_msgs/msg/CameraInfo")(d=np.array([0.1, 0.2]), distortion_model="plumb_bob")
    assert kind.deserialize(kind.serialize(info)) == info


def test_types_ros1_lacks_are_refused_naming_why() -> None:
    with pytest.raises(UnknownTypeError, match=r"example_interfaces/msg/String has no ROS 1 definition"):
        Ros1Type(TYPES, "example_interfaces/msg/String")


def _direct(name: str) -> bool:
    try:
        return Ros1Type(TYPES, name).direct
    except UnknownTypeError:
        return False  # ROS 1 lacks it, or it cannot be mapped


DIRECT = [name for name in TYPES.names() if "/msg/" in name and name in ros1_store().fielddefs and _direct(name)]


def test_most_types_need_no_conversion_and_mapped_ones_keep_it() -> None:
    assert {"std_msgs/msg/String", "std_msgs/msg/UInt8MultiArray", "geometry_msgs/msg/Twist"} <= set(DIRECT)
    assert not Ros1Type(TYPES, "sensor_msgs/msg/Image").direct  # Header.seq
    assert not Ros1Type(TYPES, "sensor_msgs/msg/CameraInfo").direct  # d vs D


@pytest.mark.parametrize("typename", DIRECT)
def test_direct_types_give_the_bytes_of_the_conversion_path(typename: str) -> None:
    """Without conversion, hetros messages become the same ROS 1 bytes (through generated code,
    cross-checked here against rosbags' serializer on the converted message) and come back equal."""
    kind = Ros1Type(TYPES, typename)
    assert kind._generated is not None, f"{typename} has no generated ROS 1 codec"
    rng = random.Random(typename)
    for _ in range(12):
        message = random_message(TYPES, typename, rng)
        slow = bytes(ros1_store().serialize_ros1(kind._outgoing(message), typename))
        assert kind.serialize(message) == slow
        decoded = kind.deserialize(bytearray(slow))
        assert decoded == message
        assert decoded.is_frozen
        assert not any(getattr(decoded, name).flags.writeable for name in decoded._array_names)


def test_damaged_ros1_bytes_name_the_field_and_offset() -> None:
    kind = Ros1Type(TYPES, "std_msgs/msg/UInt8MultiArray")
    cls = TYPES.get("std_msgs/msg/UInt8MultiArray")
    dimension = TYPES.get("std_msgs/msg/MultiArrayDimension")(label="rows", size=2, stride=4)
    data = bytes(kind.serialize(cls(layout=TYPES.get("std_msgs/msg/MultiArrayLayout")(dim=[dimension]),
                                    data=np.arange(4, dtype=np.uint8))))
    with pytest.raises(SerializationError, match=r"UInt8MultiArray.data at offset 28 needs 4 bytes"):
        kind.deserialize(data[:-1])
    with pytest.raises(SerializationError, match=r"label at offset 4 has length 4294967295"):
        kind.deserialize(data[:4] + b"\xff\xff\xff\xff" + data[8:])
    with pytest.raises(SerializationError, match=r"label at offset 8 is not UTF-8"):
        kind.deserialize(data[:8] + b"\xff" + data[9:])


SPLICED = ["sensor_msgs/msg/Image", "sensor_msgs/msg/PointCloud2", "sensor_msgs/msg/CompressedImage",
           "std_msgs/msg/UInt8MultiArray", "std_msgs/msg/Float32MultiArray", "std_msgs/msg/Int16MultiArray"]


@pytest.mark.parametrize("typename", SPLICED)
def test_large_arrays_are_spliced_into_rosbags_bytes(typename: str) -> None:
    """The pieces of a vectored write join to rosbags' own bytes, the big array sent from its memory."""
    kind = Ros1Type(TYPES, typename)
    rng = random.Random(typename)
    name, dtype = kind._spliceable[0]
    for length in (SPLICE_MIN // dtype.itemsize, SPLICE_MIN + 7, 3 * SPLICE_MIN + 1):
        message = random_message(TYPES, typename, rng)
        array = np.frombuffer(rng.randbytes(length * dtype.itemsize), dtype)
        setattr(message, name, array)
        parts = kind.serialize_parts(message)
        assert len(parts) == 4 and np.shares_memory(np.frombuffer(parts[2], np.uint8), array)
        slow = bytes(ros1_store().serialize_ros1(kind._outgoing(message), typename))
        assert b"".join(parts) == slow
        assert bytes(kind.serialize(message)) == slow


def test_small_arrays_are_serialized_whole_and_big_endian_ones_still_right() -> None:
    kind = Ros1Type(TYPES, "std_msgs/msg/Float32MultiArray")
    cls = TYPES.get("std_msgs/msg/Float32MultiArray")
    small = cls(data=np.arange(16, dtype=np.float32))
    assert kind.serialize_parts(small) == [kind.serialize(small)]
    big_endian = cls(data=np.arange(SPLICE_MIN, dtype=">f4"))
    assert b"".join(kind.serialize_parts(big_endian)) == bytes(kind.serialize(big_endian))
