"""A node module written for ROS 2 that uses a piece hetros does not provide (a check case)."""
from rclpy.parameter_client import AsyncParameterClient  # noqa: F401


def main() -> None:
    pass
