"""tf2_geometry_msgs, as ROS 1 and ROS 2 give it (its functions also under ``tf2_geometry_msgs.tf2_geometry_msgs``)."""

from .tf2_geometry_msgs import (
    do_transform_point,
    do_transform_pose,
    do_transform_pose_stamped,
    do_transform_pose_with_covariance_stamped,
    do_transform_vector3,
    do_transform_wrench,
    rotation_matrix,
    transform_points,
)

__all__ = ["do_transform_point", "do_transform_pose", "do_transform_pose_stamped",
           "do_transform_pose_with_covariance_stamped", "do_transform_vector3", "do_transform_wrench",
           "rotation_matrix", "transform_points"]
