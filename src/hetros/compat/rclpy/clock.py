"""rclpy.clock: the graph's clock (wall, or /clock's with use_sim_time)."""

from __future__ import annotations

import enum

from ...runtime import Clock


class ClockType(enum.IntEnum):
    UNINITIALIZED = 0
    ROS_TIME = 1
    SYSTEM_TIME = 2
    STEADY_TIME = 3


__all__ = ["Clock", "ClockType"]
