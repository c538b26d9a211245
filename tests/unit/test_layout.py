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
