"""tf2_py: tf2's BufferCore and exceptions, as ROS 1's and ROS 2's Python bindings give them, on hetros's
own transform tree (``_core``): what ``tf2_ros.Buffer`` builds on, and what code importing ``tf2_py as
tf2`` finds."""

from __future__ import annotations

from typing import Any

from ...msg import registry
from ._core import (
    BufferCore as _Core,
)
from ._core import (
    ConnectivityException,
    ExtrapolationException,
    InvalidArgumentException,
    LookupException,
    Pose,
    TimeoutException,
    TransformException,
    ros1_flavour,
    to_ns,
)


def stamp_of(ns: int) -> Any:
    """A header stamp: rospy.Time for rospy code, a builtin_interfaces Time otherwise."""
    if ros1_flavour():
        from ..rospy import Time as Ros1Time

        return Ros1Time(0, ns)
    if not _TIME:
        _TIME.append(registry().get("builtin_interfaces/msg/Time"))
    return _TIME[0](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


_TIME: list[Any] = []


def time_of(ns: int) -> Any:
    """A time as the flavour's API returns it: rospy.Time, or rclpy's Time."""
    if ros1_flavour():
        return stamp_of(ns)
    from ...runtime import Time

    return Time(nanoseconds=ns)


_CLASSES: list[Any] = []  # TransformStamped, Header, Transform, Vector3, Quaternion: looked up once


def transform_stamped(pose: Pose, target: str, source: str, ns: int) -> Any:
    """A lookup's answer as tf2's Python API gives it: built in one go (a lookup's cost is mostly this)."""
    if not _CLASSES:
        types = registry()
        _CLASSES.extend(types.get(name) for name in (
            "geometry_msgs/msg/TransformStamped", "std_msgs/msg/Header", "geometry_msgs/msg/Transform",
            "geometry_msgs/msg/Vector3", "geometry_msgs/msg/Quaternion"))
    stamped, header, transform, vector, quaternion = _CLASSES
    return stamped(header=header(stamp=stamp_of(ns), frame_id=target), child_frame_id=source,
                   transform=transform(translation=vector(x=pose[0], y=pose[1], z=pose[2]),
                                       rotation=quaternion(x=pose[3], y=pose[4], z=pose[5], w=pose[6])))


class BufferCore(_Core):
    """tf2_py.BufferCore: the binding's methods over the tree."""

    def lookup_transform_core(self, target_frame: str, source_frame: str, time: Any) -> Any:
        pose, ns = self.lookup_pose(target_frame, source_frame, time)
        return transform_stamped(pose, target_frame, source_frame, ns)

    def lookup_transform_full_core(self, target_frame: str, target_time: Any, source_frame: str, source_time: Any,
                                   fixed_frame: str) -> Any:
        pose, ns = self.lookup_pose_full(target_frame, target_time, source_frame, source_time, fixed_frame)
        return transform_stamped(pose, target_frame, source_frame, ns)

    def can_transform_core(self, target_frame: str, source_frame: str, time: Any) -> tuple[bool, str]:
        return self.can_lookup(target_frame, source_frame, time)

    def can_transform_full_core(self, target_frame: str, target_time: Any, source_frame: str, source_time: Any,
                                fixed_frame: str) -> tuple[bool, str]:
        return self.can_lookup_full(target_frame, target_time, source_frame, source_time, fixed_frame)

    def get_latest_common_time(self, target_frame: str, source_frame: str) -> Any:
        return time_of(self.latest_common_time(target_frame, source_frame))

    def all_frames_as_yaml(self) -> str:
        lines = []
        for row in self.describe():
            lines += [f"{row['frame']}: ", f"  parent: '{row['parent']}'", f"  broadcaster: '{row['broadcaster']}'",
                      f"  rate: {row['rate']:.3f}", f"  most_recent_transform: {row['latest'] / 1e9:.3f}",
                      f"  oldest_transform: {row['oldest'] / 1e9:.3f}",
                      f"  buffer_length: {(row['latest'] - row['oldest']) / 1e9:.3f}"]
        return "\n".join(lines) + ("\n" if lines else "")

    def all_frames_as_string(self) -> str:
        return "".join(f"Frame {row['frame']} exists with parent {row['parent']}.\n" for row in self.describe())


__all__ = [
    "BufferCore",
    "ConnectivityException",
    "ExtrapolationException",
    "InvalidArgumentException",
    "LookupException",
    "TimeoutException",
    "TransformException",
    "stamp_of",
    "time_of",
    "to_ns",
    "transform_stamped",
]
