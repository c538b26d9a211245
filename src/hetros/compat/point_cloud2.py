"""``sensor_msgs.point_cloud2`` (rospy) and ``sensor_msgs_py.point_cloud2`` (rclpy): PointCloud2 to and from
points, on numpy structured arrays.

A cloud's ``fields`` (name, offset, datatype, count) and ``point_step`` are a numpy structured dtype; making
a cloud packs the points into ``data`` with one conversion, and reading one is a view of ``data`` (no copy
until the caller asks for tuples or a plain array). Where the two libraries differ, each gets its own:
rospy's ``read_points`` yields tuples, rclpy's returns the structured array.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from .._errors import FieldValueError
from ..msg import registry

# sensor_msgs/PointField datatype -> numpy type
DATATYPES: dict[int, np.dtype[Any]] = {
    1: np.dtype(np.int8), 2: np.dtype(np.uint8), 3: np.dtype(np.int16), 4: np.dtype(np.uint16),
    5: np.dtype(np.int32), 6: np.dtype(np.uint32), 7: np.dtype(np.float32), 8: np.dtype(np.float64)}
_POINT_FIELD = "sensor_msgs/msg/PointField"


def dtype_from_fields(fields: Iterable[Any], point_step: int | None = None, bigendian: bool = False) -> np.dtype[Any]:
    """The structured dtype of a point: each field at its offset, ``point_step`` bytes in all."""
    names, formats, offsets = [], [], []
    end = 0
    for field in fields:
        if field.datatype not in DATATYPES:
            raise FieldValueError(f"PointField {field.name!r}: datatype must be one of 1..8 (INT8..FLOAT64), not "
                                  f"{field.datatype!r}")
        kind = DATATYPES[field.datatype].newbyteorder(">" if bigendian else "<")
        count = int(field.count) if field.count else 1
        names.append(field.name)
        formats.append(kind if count == 1 else np.dtype((kind, (count,))))
        offsets.append(int(field.offset))
        end = max(end, int(field.offset) + kind.itemsize * count)
    size = end if point_step is None else int(point_step)
    if size < end:
        raise FieldValueError(f"point_step must hold every field ({end} bytes), not {size!r}")
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": size})


def _points_array(points: Any, dtype: np.dtype[Any]) -> np.ndarray[Any, Any]:
    """``points`` (a structured array, an (n, fields) array, or rows of values) as records of ``dtype``."""
    if isinstance(points, np.ndarray) and points.dtype.names:
        packed = np.zeros(points.shape[0] if points.ndim else 1, dtype)
        for name in dtype.names or ():
            packed[name] = points[name]
        return packed
    rows = np.asarray(points) if not isinstance(points, np.ndarray) else points
    names = dtype.names or ()
    if rows.ndim == 2 and rows.shape[1] == len(names) and all(dtype[n].shape == () for n in names):
        packed = np.zeros(rows.shape[0], dtype)
        for index, name in enumerate(names):
            packed[name] = rows[:, index]
        return packed
    return np.array([tuple(row) for row in points], dtype=dtype)


def create_cloud(header: Any, fields: Sequence[Any], points: Any, point_step: int | None = None) -> Any:
    """A PointCloud2 of one row holding ``points``."""
    dtype = dtype_from_fields(fields, point_step)
    packed = _points_array(points, dtype)
    cloud = registry().get("sensor_msgs/msg/PointCloud2")()
    cloud.header = header
    cloud.height, cloud.width = 1, int(packed.shape[0])
    cloud.fields = list(fields)
    cloud.is_bigendian, cloud.is_dense = False, False
    cloud.point_step, cloud.row_step = dtype.itemsize, dtype.itemsize * int(packed.shape[0])
    cloud.data = np.frombuffer(packed.tobytes(), dtype=np.uint8)
    return cloud


def create_cloud_xyz32(header: Any, points: Any) -> Any:
    """A PointCloud2 of x, y, z as float32."""
    field = registry().get(_POINT_FIELD)
    fields = [field(name=name, offset=4 * index, datatype=7, count=1) for index, name in enumerate("xyz")]
    return create_cloud(header, fields, points)


def _records(cloud: Any, field_names: Sequence[str] | None, skip_nans: bool,
             uvs: Iterable[Sequence[int]] | None) -> np.ndarray[Any, Any]:
    dtype = dtype_from_fields(cloud.fields, cloud.point_step, bool(cloud.is_bigendian))
    count = int(cloud.width) * int(cloud.height)
    data = np.asarray(cloud.data, dtype=np.uint8)
    if cloud.height > 1 and cloud.row_step != cloud.width * cloud.point_step:
        rows = data.reshape(int(cloud.height), int(cloud.row_step))[:, :int(cloud.width) * int(cloud.point_step)]
        data = np.ascontiguousarray(rows).reshape(-1)
    if data.size < count * dtype.itemsize:
        raise FieldValueError(f"PointCloud2 data must hold width*height*point_step = {count * dtype.itemsize} "
                              f"bytes, not {data.size}")
    points = np.frombuffer(data.tobytes() if not data.flags.c_contiguous else data, dtype=dtype, count=count)
    if uvs is not None:
        points = points[[int(v) * int(cloud.width) + int(u) for u, v in uvs]]
    if field_names is not None:
        points = points[list(field_names)]
    if skip_nans:
        keep = np.ones(points.shape[0], dtype=bool)
        for name in points.dtype.names or ():
            if points.dtype[name].kind == "f":
                values = points[name]
                keep &= ~np.isnan(values).reshape(points.shape[0], -1).any(axis=1)
        points = points[keep]
    return points


def read_points(cloud: Any, field_names: Sequence[str] | None = None, skip_nans: bool = False,
                uvs: Iterable[Sequence[int]] | None = None, reshape_organized_cloud: bool = False) -> Any:
    """rclpy's (``sensor_msgs_py``): the points as a structured numpy array (organised clouds as
    height x width when ``reshape_organized_cloud``)."""
    points = _records(cloud, field_names, skip_nans, uvs)
    if reshape_organized_cloud and cloud.height > 1 and not skip_nans and uvs is None:
        return points.reshape(int(cloud.height), int(cloud.width))
    return points


def read_points_list(cloud: Any, field_names: Sequence[str] | None = None, skip_nans: bool = False,
                     uvs: Iterable[Sequence[int]] | None = None) -> list[tuple[Any, ...]]:
    """Each point as a tuple of its fields' values."""
    return [tuple(point) for point in _records(cloud, field_names, skip_nans, uvs).tolist()]


def read_points_numpy(cloud: Any, field_names: Sequence[str] | None = None, skip_nans: bool = False,
                      uvs: Iterable[Sequence[int]] | None = None) -> np.ndarray[Any, Any]:
    """The points as a plain (n, fields) array; the fields must share one type (rclpy's rule)."""
    points = _records(cloud, field_names, skip_nans, uvs)
    kinds = {points.dtype[name].base for name in points.dtype.names or ()}
    if len(kinds) != 1:
        raise FieldValueError(f"read_points_numpy needs fields of one type, not {sorted(map(str, kinds))}; pick "
                              "field_names of one type, or use read_points")
    return np.stack([points[name] for name in points.dtype.names or ()], axis=1)


class Ros1PointCloud2:
    """rospy's ``sensor_msgs.point_cloud2``: ``read_points`` is a generator of tuples."""

    create_cloud = staticmethod(create_cloud)
    create_cloud_xyz32 = staticmethod(create_cloud_xyz32)
    read_points_list = staticmethod(read_points_list)

    @staticmethod
    def read_points(cloud: Any, field_names: Sequence[str] | None = None, skip_nans: bool = False,
                    uvs: Iterable[Sequence[int]] | None = None) -> Iterator[tuple[Any, ...]]:
        for point in _records(cloud, field_names, skip_nans, uvs).tolist():
            yield tuple(point)


def ros1_module() -> Any:
    """The module rospy code imports as ``sensor_msgs.point_cloud2``."""
    import types

    module = types.ModuleType("sensor_msgs.point_cloud2", Ros1PointCloud2.__doc__)
    for name in ("create_cloud", "create_cloud_xyz32", "read_points", "read_points_list"):
        setattr(module, name, getattr(Ros1PointCloud2, name))
    module.DATATYPES = DATATYPES  # type: ignore[attr-defined]
    return module


__all__ = ["DATATYPES", "create_cloud", "create_cloud_xyz32", "dtype_from_fields", "read_points",
           "read_points_list", "read_points_numpy"]
