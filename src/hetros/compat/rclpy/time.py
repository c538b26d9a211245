"""rclpy.time: hetros's Time (integer nanoseconds, ``to_msg``, ``from_msg``)."""

from ...runtime import Time
from .duration import Duration

__all__ = ["Duration", "Time"]
