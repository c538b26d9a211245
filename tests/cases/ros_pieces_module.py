"""A node module written for ROS 2 that uses a piece hetros does not provide (a check case)."""
from rclpy.time_source import TimeSource  # noqa: F401


def main() -> None:
    pass
