"""rclpy.duration: hetros's Duration."""

from ...runtime import Duration

__all__ = ["Duration"]
