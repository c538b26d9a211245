"""Flat layouts, cross-checked against rosbags' CDR serializer and hand-annotated bytes."""

from __future__ import annotations

import numpy as np
import pytest

from hetros.msg import array_fields, flat_layout, registry


def test_point_layout_hand_annotated() -> None:
    layout = flat_layout(registry(), "geometry_msgs/msg/Point")
    assert layout.fixed_size and layout.size == 24
    assert [(f.path, f.offset, f.size) for f in layout.fields] == [("x", 0, 8), ("y", 8, 8), ("z", 16, 8)]
    cls = registry().get("geometry_msgs/msg/Point")
    cdr = bytes(registry().serialize(cls(x=1.0, y=-2.0, z=0.5)))
    #        encapsulation       x = 1.0 (LE float64)                 y = -2.0
    assert cdr == (b"\x00\x01\x00\x00" + b"\x00\x00\x00\x00\x00\x00\xf0\x3f" + b"\x00\x00\x00\x00\x00\x00\x00\xc0"
                   + b"\x00\x00\x00\x00\x00\x00\xe0\x3f")  # z = 0.5
    record = layout.view(cdr)
    assert (record["x"], record["y"], record["z"]) == (1.0, -2.0, 0.5)


def test_alignment_padding_matches_cdr() -> None:
    # Imu-like mix: Vector3Stamped has a string; use a fixed type with mixed widths instead.
    layout = flat_layout(registry(), "sensor_msgs/msg/RegionOfInterest")
    assert [(f.path, f.offset) for f in layout.fields] == [
        ("x_offset", 0), ("y_offset", 4), ("height", 8), ("width", 12), ("do_rectify", 16)]
    cls = registry().get("sensor_msgs/msg/RegionOfInterest")
    msg = cls(x_offset=1, y_offset=2, height=3, width=4, do_rectify=True)
    record = layout.view(bytes(registry().serialize(msg)))
    assert (record["x_offset"], record["width"], bool(record["do_rectify"])) == (1, 4, True)


@pytest.mark.parametrize("typename", [
    "geometry_msgs/msg/Pose", "geometry_msgs/msg/PoseWithCovariance", "geometry_msgs/msg/Twist",
    "geometry_msgs/msg/TwistWithCovariance", "geometry_msgs/msg/Accel",
])
def test_flat_view_equals_deserialization_for_random_messages(typename: str) -> None:
    """The fast path (a numpy view on the CDR bytes) against the slow reference (rosbags)."""
    rng = np.random.default_rng(7)
    layout = flat_layout(registry(), typename)
    assert layout.fixed_size
    cls = registry().get(typename)
    message = cls()
    values: dict[str, object] = {}
    for field in layout.fields:
        holder = message
        *parents, last = field.path.split(".")
        for name in parents:
            holder = getattr(holder, name)
        value = rng.normal(size=field.count) if field.count > 1 else float(rng.normal())
        setattr(holder, last, value)
        values[field.path] = value
    cdr = bytes(registry().serialize(message))
    assert len(cdr) == 4 + (layout.size or 0)
    record = layout.view(cdr)
    for path, value in values.items():
        assert np.allclose(record[path], value), path


def test_variable_fields_are_marked() -> None:
    layout = flat_layout(registry(), "sensor_msgs/msg/Image")
    assert not layout.fixed_size
    kinds = {f.path: f.variable for f in layout.fields}
    assert kinds["header.stamp.sec"] is False and kinds["header.frame_id"] is True and kinds["data"] is True
    assert "var" in layout.describe()


def test_array_fields_reach_into_nested_messages() -> None:
    fields = array_fields(registry(), "geometry_msgs/msg/PoseWithCovarianceStamped")
    assert [(f.path, f.length) for f in fields] == [(("pose", "covariance"), 36)]
    assert [f.path for f in array_fields(registry(), "sensor_msgs/msg/PointCloud2")] == [("data",)]


def _evaluate(expression: str, lengths: list[int]) -> int:
    """An offset expression of ``msg layout`` (``a4(12+n1)+8``) for the given length words."""
    import re

    text = re.sub(r"n(\d+)", lambda m: str(lengths[int(m[1]) - 1]), expression)
    text = re.sub(r"a(\d)\(", r"_a(\1, ", text)
    return int(eval(text, {"_a": lambda n, x: (x + n - 1) // n * n}))


def test_offsets_after_a_string_are_expressions_that_hold_on_the_wire() -> None:
    """`hetros msg layout sensor_msgs/msg/Image`: each offset after frame_id, evaluated with the message's
    length words, is where the encoded field is."""
    import struct

    from hetros.interfaces.sensor_msgs.msg import Image

    types = registry()
    layout = flat_layout(types, "sensor_msgs/msg/Image")
    image = Image(height=3, width=7, encoding="mono16", is_bigendian=1, step=14, data=np.arange(5, dtype=np.uint8))
    image.header.frame_id = "camera"
    codec = types.codec("sensor_msgs/msg/Image")
    wire = bytearray(codec.size(image))
    codec.encode(image, memoryview(wire))
    body = bytes(wire)  # the codec writes the body (the transports add the encapsulation header)
    lengths = [len("camera") + 1, len("mono16") + 1, 5]
    found = {f.path: f for f in layout.fields}
    for path, fmt, value in (("height", "<I", 3), ("width", "<I", 7), ("is_bigendian", "<B", 1), ("step", "<I", 14)):
        at = _evaluate(found[path].at, lengths)
        assert struct.unpack_from(fmt, body, at)[0] == value, (path, found[path].at, at)
    data_at = _evaluate(found["data"].at, lengths)
    assert struct.unpack_from("<I", body, data_at)[0] == 5 and body[data_at + 4:data_at + 9] == bytes(range(5))
    assert "a4(12+n1)" in layout.describe() and "nK: the K-th length word" in layout.describe()
