"""rclpy.utilities: the command-line helpers ROS 2 nodes use when they parse their own arguments."""

from __future__ import annotations

import sys

from . import get_default_context, ok, shutdown, try_shutdown


def remove_ros_args(args: list[str] | None = None) -> list[str]:
    """``args`` (else ``sys.argv``, the node's own under hetros) without ROS's sections: each
    ``--ros-args`` up to the next ``--`` (or the end), and a lone ``--ros-args``."""
    kept: list[str] = []
    inside = False
    for arg in sys.argv if args is None else args:
        if arg == "--ros-args":
            inside = True
        elif inside and arg == "--":
            inside = False
        elif not inside:
            kept.append(arg)
    return kept


def get_rmw_implementation_identifier() -> str:
    """The middleware, as ROS 2 names it: hetros's planned transports (ROS 2 peers meet it over CycloneDDS)."""
    return "rmw_hetros"


def timeout_sec_to_nsec(timeout_sec: float | None) -> int:
    """rclpy's conversion: None or a negative timeout waits forever (-1), else nanoseconds."""
    if timeout_sec is None or timeout_sec < 0:
        return -1
    return int(float(timeout_sec) * 1e9)


def get_available_rmw_implementations() -> set[str]:
    return {get_rmw_implementation_identifier()}




__all__ = [
    "get_available_rmw_implementations",
    "get_default_context",
    "get_rmw_implementation_identifier",
    "ok",
    "remove_ros_args",
    "shutdown",
    "timeout_sec_to_nsec",
    "try_shutdown",
]
