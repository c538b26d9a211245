"""sensor_msgs.point_cloud2 (rospy) and sensor_msgs_py.point_cloud2 (rclpy) on hetros's messages: clouds made
and read back, against bytes worked out by hand."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from hetros import FieldValueError
from hetros.compat import point_cloud2
from hetros.msg import registry

PointField = registry().get("sensor_msgs/msg/PointField")
Header = registry().get("std_msgs/msg/Header")


def _xyzi() -> list[object]:
    return [PointField(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate(("x", "y", "z", "i"))]


def test_a_cloud_packs_points_at_their_offsets() -> None:
    cloud = point_cloud2.create_cloud(Header(frame_id="map"), _xyzi(), [(1.0, 2.0, 3.0, 4.0), (5.0, 6.0, 7.0, 8.0)])
    assert (cloud.height, cloud.width, cloud.point_step, cloud.row_step) == (1, 2, 16, 32)
    assert bytes(cloud.data) == struct.pack("<8f", 1, 2, 3, 4, 5, 6, 7, 8)
    assert point_cloud2.read_points_list(cloud, field_names=("z", "x")) == [(3.0, 1.0), (7.0, 5.0)]


def test_an_n_by_fields_array_a_structured_array_and_rows_make_the_same_cloud() -> None:
    rows = np.arange(8, dtype=np.float64).reshape(2, 4)
    structured = np.zeros(2, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("i", "f4")])
    for index, name in enumerate("xyzi"):
        structured[name] = rows[:, index]
    made = [bytes(point_cloud2.create_cloud(Header(), _xyzi(), points).data)
            for points in (rows, structured, rows.tolist())]
    assert made[0] == made[1] == made[2] == struct.pack("<8f", *range(8))


def test_read_points_skips_nans_and_picks_pixels() -> None:
    cloud = point_cloud2.create_cloud_xyz32(Header(), [(1, 2, 3), (4, 5, float("nan")), (7, 8, 9)])
    assert point_cloud2.read_points_list(cloud, skip_nans=True) == [(1.0, 2.0, 3.0), (7.0, 8.0, 9.0)]
    assert point_cloud2.read_points_list(cloud, uvs=[(2, 0)]) == [(7.0, 8.0, 9.0)]
    assert point_cloud2.read_points_numpy(cloud, field_names=["x", "y"]).tolist() == [[1, 2], [4, 5], [7, 8]]
    assert point_cloud2.read_points(cloud).dtype.names == ("x", "y", "z")


def test_rospys_read_points_yields_tuples() -> None:
    ros1 = point_cloud2.ros1_module()
    cloud = ros1.create_cloud_xyz32(Header(), [(1, 2, 3)])
    assert list(ros1.read_points(cloud)) == [(1.0, 2.0, 3.0)]


def test_bad_fields_and_short_data_are_named() -> None:
    with pytest.raises(FieldValueError, match=r"datatype must be one of 1\.\.8"):
        point_cloud2.create_cloud(Header(), [PointField(name="x", offset=0, datatype=9, count=1)], [(1,)])
    cloud = point_cloud2.create_cloud_xyz32(Header(), [(1, 2, 3)])
    cloud.width = 2
    with pytest.raises(FieldValueError, match="must hold width\\*height\\*point_step = 24 bytes, not 12"):
        point_cloud2.read_points_list(cloud)
