"""rclpy.clock: the graph's clock (wall, or /clock's with use_sim_time)."""

from __future__ import annotations

import enum
from typing import Any

from ..._errors import Error
from ...runtime import Clock, Time, bound_node


class ClockType(enum.IntEnum):
    UNINITIALIZED = 0
    ROS_TIME = 1
    SYSTEM_TIME = 2
    STEADY_TIME = 3


class ROSClock(Clock):
    """rclpy's ROSClock: the node's clock (/clock's with use_sim_time), the wall clock outside a node."""

    def _clock(self) -> Any:
        try:
            return bound_node().get_clock()
        except Error:
            return None

    def now(self) -> Time:
        clock = self._clock()
        return Clock.now(self) if clock is None else clock.now()

    def now_ns(self) -> int:
        clock = self._clock()
        return Clock.now_ns(self) if clock is None else int(clock.now_ns())


__all__ = ["Clock", "ClockType", "ROSClock"]
