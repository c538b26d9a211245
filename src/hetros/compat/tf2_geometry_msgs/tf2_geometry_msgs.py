"""tf2_geometry_msgs: geometry_msgs' stamped types moved into another frame by a TransformStamped
(``do_transform_*``), registered so that ``Buffer.transform(msg, frame)`` finds them. A result's header is
the transform's (its target frame and stamp), as in tf2_geometry_msgs. ``transform_points`` moves a batch
of points as one numpy operation."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from ...msg import registry
from ..tf2_py._core import Pose, compose, rotate
from ..tf2_ros.buffer_interface import TransformRegistration


def _pose_of(transform: Any) -> Pose:
    t, r = transform.transform.translation, transform.transform.rotation
    return (float(t.x), float(t.y), float(t.z), float(r.x), float(r.y), float(r.z), float(r.w))


def _new(typename: str, header: Any) -> Any:
    message = registry().get(typename)()
    message.header = copy.deepcopy(header)
    return message


def rotation_matrix(transform: Any) -> np.ndarray:
    """The 3x3 rotation of a TransformStamped."""
    _x, _y, _z, qx, qy, qz, qw = _pose_of(transform)
    return np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])


def transform_points(points: np.ndarray, transform: Any) -> np.ndarray:
    """An (N, 3) array of points moved by ``transform``: one matrix product, not a Python loop."""
    array = np.asarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"points must be an array of shape (N, 3), not {array.shape}")
    t = transform.transform.translation
    moved: np.ndarray = array @ rotation_matrix(transform).T + np.array([t.x, t.y, t.z])
    return moved


def _moved_point(pose: Pose, x: float, y: float, z: float) -> tuple[float, float, float]:
    rx, ry, rz = rotate(pose[3], pose[4], pose[5], pose[6], x, y, z)
    return rx + pose[0], ry + pose[1], rz + pose[2]


def do_transform_point(point: Any, transform: Any) -> Any:
    pose = _pose_of(transform)
    result = _new("geometry_msgs/msg/PointStamped", transform.header)
    result.point.x, result.point.y, result.point.z = _moved_point(pose, point.point.x, point.point.y, point.point.z)
    return result


def do_transform_vector3(vector3: Any, transform: Any) -> Any:
    pose = _pose_of(transform)
    result = _new("geometry_msgs/msg/Vector3Stamped", transform.header)
    v = vector3.vector
    result.vector.x, result.vector.y, result.vector.z = rotate(pose[3], pose[4], pose[5], pose[6], v.x, v.y, v.z)
    return result


def _moved_pose(pose_message: Any, transform_pose: Pose) -> Any:
    p, o = pose_message.position, pose_message.orientation
    moved = compose(transform_pose, (float(p.x), float(p.y), float(p.z), float(o.x), float(o.y), float(o.z),
                                     float(o.w)))
    result = registry().get("geometry_msgs/msg/Pose")()
    result.position.x, result.position.y, result.position.z = moved[:3]
    # of a rotation's two quaternions, tf2_geometry_msgs gives the one with w >= 0
    sign = -1.0 if moved[6] < 0 else 1.0
    result.orientation.x, result.orientation.y, result.orientation.z, result.orientation.w = \
        (sign * v + 0.0 for v in moved[3:])
    return result


def do_transform_pose(pose: Any, transform: Any) -> Any:
    """A Pose (ROS 2's signature; a PoseStamped is moved by ``do_transform_pose_stamped``)."""
    if hasattr(pose, "header"):
        return do_transform_pose_stamped(pose, transform)
    return _moved_pose(pose, _pose_of(transform))


def do_transform_pose_stamped(pose: Any, transform: Any) -> Any:
    result = _new("geometry_msgs/msg/PoseStamped", transform.header)
    result.pose = _moved_pose(pose.pose, _pose_of(transform))
    return result


def _rotated_covariance(covariance: Any, transform: Any) -> np.ndarray:
    rotation = rotation_matrix(transform)
    block = np.zeros((6, 6))
    block[:3, :3] = block[3:, 3:] = rotation
    return (block @ np.asarray(covariance, dtype=np.float64).reshape(6, 6) @ block.T).reshape(36)


def do_transform_pose_with_covariance_stamped(pose: Any, transform: Any) -> Any:
    result = _new("geometry_msgs/msg/PoseWithCovarianceStamped", transform.header)
    result.pose.pose = _moved_pose(pose.pose.pose, _pose_of(transform))
    result.pose.covariance = _rotated_covariance(pose.pose.covariance, transform)
    return result


def do_transform_wrench(wrench: Any, transform: Any) -> Any:
    """Force and torque rotated into the target frame (tf2_geometry_msgs's Python version: rotations)."""
    pose = _pose_of(transform)
    result = _new("geometry_msgs/msg/WrenchStamped", transform.header)
    for name in ("force", "torque"):
        v = getattr(wrench.wrench, name)
        out = getattr(result.wrench, name)
        out.x, out.y, out.z = rotate(pose[3], pose[4], pose[5], pose[6], v.x, v.y, v.z)
    return result


def _register() -> None:
    registration = TransformRegistration()
    for typename, function in (("geometry_msgs/msg/PointStamped", do_transform_point),
                               ("geometry_msgs/msg/Vector3Stamped", do_transform_vector3),
                               ("geometry_msgs/msg/PoseStamped", do_transform_pose_stamped),
                               ("geometry_msgs/msg/PoseWithCovarianceStamped",
                                do_transform_pose_with_covariance_stamped),
                               ("geometry_msgs/msg/WrenchStamped", do_transform_wrench)):
        registration.add(typename, function)


_register()

__all__ = ["do_transform_point", "do_transform_pose", "do_transform_pose_stamped",
           "do_transform_pose_with_covariance_stamped", "do_transform_vector3", "do_transform_wrench",
           "rotation_matrix", "transform_points"]
