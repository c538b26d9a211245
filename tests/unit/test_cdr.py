"""The generated CDR codecs against rosbags (the reference) and against hand-annotated bytes."""

from __future__ import annotations

import random
import struct

import numpy as np
import pytest

from hetros import SerializationError
from hetros.msg import TypeRegistry, array_fields, copy, get_path, set_path
from hetros.msg._cdr import reference_codec
from tests.support.messages import random_message

TYPES = TypeRegistry()
MESSAGE_TYPES = [name for name in TYPES.names() if "/msg/" in name or "/srv/" in name or "/action/" in name]


def _encode(codec_size: object, codec_encode: object, message: object) -> bytes:
    size = codec_size(message)  # type: ignore[operator]
    buffer = memoryview(bytearray(b"\xee" * size))  # stale bytes must not leak into padding
    end = codec_encode(message, buffer)  # type: ignore[operator]
    assert end == size
    return bytes(buffer)


def _lean(message: object, typename: str) -> object:
    clone = copy(message)  # type: ignore[arg-type]
    for field in array_fields(TYPES, typename):
        if field.length is None:
            set_path(clone, field.path, get_path(clone, field.path)[:0])
    return clone


@pytest.mark.parametrize("typename", MESSAGE_TYPES)
def test_generated_codec_matches_rosbags_on_random_messages(typename: str) -> None:
    codec = TYPES.codec(typename)
    assert codec.generated, f"{typename} fell back to rosbags"
    rnd = random.Random(typename)
    for _ in range(12):
        message = random_message(TYPES, typename, rnd)
        reference = bytes(TYPES.serialize(message))[4:]
        assert _encode(codec.size, codec.encode, message) == reference
        buffer = bytearray(reference)
        decoded = codec.decode(memoryview(buffer).toreadonly())
        assert decoded == message
        assert decoded.is_frozen
        if codec.decode_copies:  # the transports reuse the bytes at once: nothing may point into them
            assert not _holds_array(decoded)
            buffer[:] = b"\xee" * len(buffer)
            assert decoded == message
        lean_reference = bytes(TYPES.serialize(_lean(message, typename)))[4:]  # type: ignore[arg-type]
        assert _encode(codec.size_lean, codec.encode_lean, message) == lean_reference


def _holds_array(value: object) -> bool:
    if isinstance(value, np.ndarray):
        return True
    if isinstance(value, list):
        return any(_holds_array(item) for item in value)
    names = getattr(value, "__fieldnames__", ())
    return any(_holds_array(getattr(value, name)) for name in names)


@pytest.mark.parametrize(("typename", "copies"), [
    ("std_msgs/msg/String", True), ("geometry_msgs/msg/Twist", True), ("geometry_msgs/msg/PoseArray", True),
    ("nav_msgs/msg/Path", True), ("sensor_msgs/msg/Image", False), ("sensor_msgs/msg/Imu", False),
    ("sensor_msgs/msg/PointCloud2", False),
])
def test_decode_copies_only_for_types_without_primitive_arrays(typename: str, copies: bool) -> None:
    """``decode_copies`` lets shared memory return a sample before the message is used."""
    assert TYPES.codec(typename).decode_copies is copies


def test_reference_codec_is_rosbags_behind_the_same_interface() -> None:
    typename = "sensor_msgs/msg/PointCloud2"
    reference = reference_codec(TYPES, typename)
    generated = TYPES.codec(typename)
    rnd = random.Random(7)
    for _ in range(20):
        message = random_message(TYPES, typename, rnd)
        data = _encode(reference.size, reference.encode, message)
        assert data == _encode(generated.size, generated.encode, message)
        assert reference.decode(memoryview(data)) == generated.decode(memoryview(data))


def _image() -> object:
    Image = TYPES.get("sensor_msgs/msg/Image")
    message = Image(height=2, width=3, encoding="rgb8", is_bigendian=1, step=9,
                    data=np.array([1, 2, 3], np.uint8))
    message.header.stamp.sec = -2
    message.header.stamp.nanosec = 7
    message.header.frame_id = "ab"
    return message


# sensor_msgs/Image, hand-annotated (offsets from the start of the CDR body)
IMAGE = bytes.fromhex(
    "feffffff"          # 0  header.stamp.sec = -2 (int32)
    "07000000"          # 4  header.stamp.nanosec = 7
    "03000000" "616200" # 8  header.frame_id: length 3 (with NUL), "ab\0"
    "00"                # 15 padding to 4
    "02000000"          # 16 height = 2
    "03000000"          # 20 width = 3
    "05000000" "7267623800"  # 24 encoding: length 5, "rgb8\0"
    "01"                # 33 is_bigendian = 1 (uint8: no padding before it)
    "0000"              # 34 padding to 4
    "09000000"          # 36 step = 9
    "03000000" "010203" # 40 data: 3 elements
)


def test_image_bytes_as_annotated() -> None:
    codec = TYPES.codec("sensor_msgs/msg/Image")
    message = _image()
    assert _encode(codec.size, codec.encode, message) == IMAGE
    decoded = codec.decode(memoryview(IMAGE))
    assert decoded == message
    assert decoded.data.base is not None  # a view on the bytes, not a copy


# geometry_msgs/PoseWithCovariance: the float64 after a 4-byte position is aligned to 8
def test_alignment_padding_is_zero_and_static_where_known() -> None:
    Imu = TYPES.get("sensor_msgs/msg/Imu")
    message = Imu()
    message.header.frame_id = "abc"  # 4 + 4 + 4 + 4 bytes: the quaternion's float64 starts at 16
    data = _encode(TYPES.codec("sensor_msgs/msg/Imu").size, TYPES.codec("sensor_msgs/msg/Imu").encode, message)
    assert data[8:16] == struct.pack("<I", 4) + b"abc\0"
    assert data == bytes(TYPES.serialize(message))[4:]


@pytest.mark.parametrize(("damage", "expected"), [
    (lambda b: b[:30], r"Image\.encoding at offset 24 has length 5, which does not fit"),
    (lambda b: b[:10], r"Image\.header\.stamp\.sec at offset 0 needs 12 bytes, but the message ends at offset 10"),
    (lambda b: b[:8] + struct.pack("<I", 2**31) + b[12:], r"Image\.header\.frame_id at offset 8 has length 2147483648"),
    (lambda b: b[:12] + b"a\xff\0" + b[15:], r"Image\.header\.frame_id at offset 13 is not UTF-8"),
    (lambda b: b[:12] + b"abc" + b[15:],
     r"Image\.header\.frame_id at offset 8: string of length 3 does not end in NUL"),
    (lambda b: b[:40] + struct.pack("<I", 9) + b[44:], r"Image\.data at offset 44 needs 9 bytes"),
])
def test_damaged_bytes_name_the_field_and_offset(damage: object, expected: str) -> None:
    codec = TYPES.codec("sensor_msgs/msg/Image")
    with pytest.raises(SerializationError, match=expected):
        codec.decode(memoryview(damage(IMAGE)))  # type: ignore[operator]


def test_bounded_sequence_over_its_bound_is_refused(tmp_path: object) -> None:
    from pathlib import Path

    package = Path(str(tmp_path)) / "bounded_pkg"
    (package / "msg").mkdir(parents=True)
    (package / "msg" / "Few.msg").write_text("int16[<=2] values\n")
    types = TypeRegistry()
    types.load_folder(package)
    codec = types.codec("bounded_pkg/msg/Few")
    data = struct.pack("<I3h", 3, 1, 2, 3)
    with pytest.raises(SerializationError, match=r"Few\.values at offset 0 has 3 elements, more than its bound of 2"):
        codec.decode(memoryview(data))


def test_codecs_work_at_an_offset_of_a_larger_buffer() -> None:
    """The transports encode and decode in place in a slot, after their own header."""
    codec = TYPES.codec("sensor_msgs/msg/Image")
    message = _image()
    buffer = memoryview(bytearray(32 + len(IMAGE) + 8))
    assert codec.encode(message, buffer, 32) == 32 + len(IMAGE)
    assert bytes(buffer[32:32 + len(IMAGE)]) == IMAGE
    assert codec.decode(buffer, 32, 32 + len(IMAGE)) == message
    with pytest.raises(SerializationError, match=r"Image\.data at offset 76 needs 3 bytes"):
        codec.decode(buffer, 32, 32 + len(IMAGE) - 1)


def test_strided_arrays_encode_like_their_contiguous_copy() -> None:
    """rosbags refuses strided float arrays; the generated codec writes them like a copy."""
    Floats = TYPES.get("std_msgs/msg/Float64MultiArray")
    message = Floats(data=np.arange(10, dtype=np.float64)[::3])
    codec = TYPES.codec("std_msgs/msg/Float64MultiArray")
    contiguous = Floats(data=message.data.copy())
    assert _encode(codec.size, codec.encode, message) == bytes(TYPES.serialize(contiguous))[4:]
    Bytes = TYPES.get("std_msgs/msg/UInt8MultiArray")
    message = Bytes(data=np.arange(20, dtype=np.uint8)[::2])
    codec = TYPES.codec("std_msgs/msg/UInt8MultiArray")
    assert _encode(codec.size, codec.encode, message) == bytes(TYPES.serialize(message))[4:]
