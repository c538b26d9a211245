"""rclpy.timer: the timer and rate a node creates."""

from .node import Rate, Timer

__all__ = ["Rate", "Timer"]
