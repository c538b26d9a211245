"""One rule for field values in every mapping: refused at publish with field, type and value.

The validator is cross-checked against rosbags: every message it accepts serializes and
round-trips, every value rosbags cannot carry is refused first.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hetros import FieldValueError, Node
from hetros.msg import registry, validate

TYPES = ["std_msgs/msg/Int32", "std_msgs/msg/String", "std_msgs/msg/Float32", "std_msgs/msg/Bool",
         "std_msgs/msg/UInt8MultiArray", "sensor_msgs/msg/Image", "geometry_msgs/msg/PoseWithCovariance",
         "std_msgs/msg/Int8", "std_msgs/msg/UInt64"]

odd_values = st.one_of(
    st.none(), st.booleans(), st.integers(-2**70, 2**70), st.floats(), st.text(max_size=5), st.binary(max_size=4),
    st.lists(st.integers(-300, 300), max_size=5), st.lists(st.floats(-1e3, 1e3), max_size=5),
    st.lists(st.text(max_size=2), max_size=3), st.builds(lambda n: np.arange(n, dtype=np.int64), st.integers(0, 40)),
    st.builds(lambda n: np.zeros(n, np.float32), st.integers(0, 40)),
)


def _set(message: Any, field: str, value: Any) -> Any:
    """``message`` with ``field`` assigned after construction (None given to the constructor is the default)."""
    setattr(message, field, value)
    return message


@pytest.mark.parametrize(("make", "message"), [
    (lambda c: c(data=5), "String.data must be a str, not 5 (int)"),
    (lambda c: _set(c(), "data", None), "String.data must be a str, not None (NoneType)"),
])
def test_string_values(make: Any, message: str) -> None:
    with pytest.raises(FieldValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        validate(make(registry().get("std_msgs/msg/String")))


def test_integer_range_and_kind() -> None:
    cls = registry().get("std_msgs/msg/Int32")
    with pytest.raises(FieldValueError, match=r"Int32.data must be int32 \(-2147483648..2147483647\), not 2\*\*40|"
                                              r"not 1099511627776"):
        validate(cls(data=2**40))
    with pytest.raises(FieldValueError, match="must be an int"):
        validate(cls(data=1.0))
    with pytest.raises(FieldValueError, match="must be an int"):
        validate(cls(data=True))
    validate(cls(data=np.int16(7)))


def test_integer_arrays_refuse_floats_instead_of_truncating() -> None:
    cls = registry().get("std_msgs/msg/UInt8MultiArray")
    with pytest.raises(FieldValueError, match="no float64 values into uint8: they would be truncated"):
        cls(data=[1.5, 2.5])
    with pytest.raises(FieldValueError, match=r"values in 0\.\.255 for uint8, not 300"):
        cls(data=[1, 300])
    assert cls(data=[1, 2]).data.dtype == np.uint8
    message = cls()
    message.data = [1.5]
    with pytest.raises(FieldValueError, match=r"UInt8MultiArray.data must be a sequence of uint8"):
        validate(message)


def test_fixed_arrays_and_nested_messages_name_the_path() -> None:
    pose = registry().get("geometry_msgs/msg/PoseWithCovariance")()
    pose.covariance = np.zeros(35)
    with pytest.raises(FieldValueError, match=r"PoseWithCovariance\.covariance must have exactly 36 elements, not 35"):
        validate(pose)
    image = registry().get("sensor_msgs/msg/Image")()
    image.header.stamp.sec = "now"
    with pytest.raises(FieldValueError, match=r"Image.header.stamp.sec must be an int \(int32\), not 'now'"):
        validate(image)
    image = registry().get("sensor_msgs/msg/Image")()
    image.header = "x"
    with pytest.raises(FieldValueError, match=r"Image\.header must be a std_msgs/msg/Header"):
        validate(image)


def test_publish_refuses_in_a_standalone_node() -> None:
    node = Node("n")
    pub = node.create_publisher(registry().get("std_msgs/msg/String"), "/s")
    with pytest.raises(FieldValueError, match=r"String\.data must be a str"):
        pub.publish(registry().get("std_msgs/msg/String")(data=b"bytes"))


@settings(max_examples=600, deadline=None, derandomize=True, database=None)
@given(st.sampled_from(TYPES), st.data())
def test_validator_agrees_with_rosbags(typename: str, data: st.DataObject) -> None:
    types = registry()
    cls = types.get(typename)
    message = cls()
    for name in cls.__fieldnames__:
        if data.draw(st.booleans()):
            try:
                setattr(message, name, data.draw(odd_values))
            except FieldValueError:
                pass
    try:
        validate(message)
    except FieldValueError:
        return
    wire = bytes(types.serialize(message))
    decoded = types.deserialize(wire, typename)
    assert bytes(types.serialize(decoded)) == wire, "float32 rounds as on the wire; everything else is exact"
    if "Float32" not in typename:
        assert decoded == message
