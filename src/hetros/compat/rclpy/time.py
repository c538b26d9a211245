"""rclpy.time: hetros's Time (integer nanoseconds, ``to_msg``, ``from_msg``)."""

from ...runtime import Time

__all__ = ["Time"]
