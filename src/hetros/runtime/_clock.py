"""One clock per graph: wall time, or the simulated time a replay or a simulator publishes on ``/clock``.

``node.get_clock().now()``, ``node.create_timer`` and ``node.rate`` all read it, so that a node
stamped and paced by it behaves the same against recorded time (``hetros play --clock``) as
against the wall. rclpy's shapes are kept: ``Time`` and ``Duration`` in integer nanoseconds,
``Time.to_msg()`` for a header stamp.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from functools import total_ordering
from typing import TYPE_CHECKING, Any

from .._errors import NodeError
from .._qos import MAX_PERIOD, MIN_PERIOD
from ..msg import registry
from ..plan import CLOCK_TOPIC, CLOCK_TYPE

if TYPE_CHECKING:
    from ._executor import Executor
    from ._node import Node

_NS = 1_000_000_000


class Duration:
    """A span of time in integer nanoseconds (rclpy.duration.Duration)."""

    __slots__ = ("nanoseconds",)

    def __init__(self, *, seconds: float = 0, nanoseconds: int = 0) -> None:
        self.nanoseconds = int(seconds * _NS) + int(nanoseconds)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Duration) and other.nanoseconds == self.nanoseconds

    def __lt__(self, other: Duration) -> bool:
        return self.nanoseconds < other.nanoseconds

    def __hash__(self) -> int:
        return hash(self.nanoseconds)

    def __repr__(self) -> str:
        return f"Duration(nanoseconds={self.nanoseconds})"

    def to_msg(self) -> Any:
        seconds, nanoseconds = divmod(self.nanoseconds, _NS)
        return registry().get("builtin_interfaces/msg/Duration")(sec=seconds, nanosec=nanoseconds)


@total_ordering
class Time:
    """A point in time of one clock, in integer nanoseconds since its epoch (rclpy.time.Time)."""

    __slots__ = ("clock_type", "nanoseconds")

    def __init__(self, *, seconds: float = 0, nanoseconds: int = 0, clock_type: str = "ROS_TIME") -> None:
        self.nanoseconds = int(seconds * _NS) + int(nanoseconds)
        if self.nanoseconds < 0:
            raise NodeError(f"a time must not be negative, not {self.nanoseconds} ns")
        self.clock_type = clock_type

    @classmethod
    def from_msg(cls, message: Any, clock_type: str = "ROS_TIME") -> Time:
        """From a ``builtin_interfaces/msg/Time`` (a header's stamp)."""
        return cls(nanoseconds=int(message.sec) * _NS + int(message.nanosec), clock_type=clock_type)

    def to_msg(self) -> Any:
        """As a ``builtin_interfaces/msg/Time``, for a header's stamp."""
        seconds, nanoseconds = divmod(self.nanoseconds, _NS)
        return registry().get("builtin_interfaces/msg/Time")(sec=seconds, nanosec=nanoseconds)

    def seconds_nanoseconds(self) -> tuple[int, int]:
        return divmod(self.nanoseconds, _NS)

    def __sub__(self, other: Time | Duration) -> Any:
        if isinstance(other, Time):
            return Duration(nanoseconds=self.nanoseconds - other.nanoseconds)
        return Time(nanoseconds=self.nanoseconds - other.nanoseconds, clock_type=self.clock_type)

    def __add__(self, other: Duration) -> Time:
        return Time(nanoseconds=self.nanoseconds + other.nanoseconds, clock_type=self.clock_type)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Time) and other.nanoseconds == self.nanoseconds

    def __lt__(self, other: Time) -> bool:
        return self.nanoseconds < other.nanoseconds

    def __hash__(self) -> int:
        return hash(self.nanoseconds)

    def __repr__(self) -> str:
        return f"Time(nanoseconds={self.nanoseconds}, clock_type={self.clock_type})"


class Clock:
    """Wall time (``ROS_TIME`` without ``use_sim_time``: the system clock, as ROS 2's)."""

    simulated = False

    def now(self) -> Time:
        return Time(nanoseconds=time.time_ns())

    def now_ns(self) -> int:
        return time.time_ns()

    def wait_until(self, due_ns: int, stop: threading.Event) -> bool:
        """Sleep until this clock reads ``due_ns``; False when the graph stopped first."""
        delay = (due_ns - time.time_ns()) / _NS
        return not (delay > 0 and stop.wait(delay))

    def on_advance(self, hook: Callable[[], None]) -> None:
        """Wall time advances by itself: nobody needs telling."""

    def close(self) -> None:
        pass


class SimulatedClock(Clock):
    """The time last published on ``/clock`` (``rosgraph_msgs/msg/Clock``): 0 until the first message;
    it moves only when a replay or a simulator moves it."""

    simulated = True

    def __init__(self, stop: threading.Event) -> None:
        self._stop = stop
        self._now = 0
        self._changed = threading.Condition()
        self._hooks: list[Callable[[], None]] = []

    def set(self, nanoseconds: int) -> None:
        with self._changed:
            if nanoseconds < self._now:
                return  # a replay looping back restarts no timer: ROS 2 would jump back; hetros keeps time monotonic
            self._now = nanoseconds
            self._changed.notify_all()
            hooks = list(self._hooks)
        for hook in hooks:
            hook()

    def now(self) -> Time:
        return Time(nanoseconds=self._now)

    def now_ns(self) -> int:
        return self._now

    def wait_until(self, due_ns: int, stop: threading.Event) -> bool:
        with self._changed:
            while self._now < due_ns:
                if stop.is_set() or self._stop.is_set():
                    return False
                self._changed.wait(0.1)
        return True

    def on_advance(self, hook: Callable[[], None]) -> None:
        with self._changed:
            self._hooks.append(hook)

    def close(self) -> None:
        with self._changed:
            self._hooks.clear()
            self._changed.notify_all()


def check_period(seconds: object, what: str) -> float:
    """``seconds`` as a timer's or a rate's period; NodeError naming ``what`` for anything that is not a
    finite number of seconds in range (``nan``, a string, 0, ``1/1e-320`` = inf would hang or spin)."""
    if isinstance(seconds, bool) or not isinstance(seconds, int | float) or \
            not MIN_PERIOD <= seconds <= MAX_PERIOD:
        raise NodeError(f"{what} must be a period of {MIN_PERIOD:g} to {MAX_PERIOD:g} s, not {seconds!r}")
    return float(seconds)


def check_hz(hz: object, what: str) -> float:
    """``hz`` as a rate: a finite number whose period :func:`check_period` takes."""
    if isinstance(hz, bool) or not isinstance(hz, int | float) or not 1 / MAX_PERIOD <= hz <= 1 / MIN_PERIOD:
        raise NodeError(f"{what} must be a rate of {1 / MAX_PERIOD:g} to {1 / MIN_PERIOD:g} Hz, not {hz!r}")
    return float(hz)


class Ticker:
    """The due times of a fixed period on a clock, as rclpy's and rospy's ``Rate`` keep them: a sleeper
    that fell more than a period behind starts again from now instead of catching up."""

    def __init__(self, clock: Clock, period_ns: int) -> None:
        self.clock = clock
        self.period_ns = period_ns
        self.due = clock.now_ns() + period_ns

    def sleep(self, stop: threading.Event) -> bool:
        """Sleep until the next due time; False when ``stop`` was set first."""
        if not self.clock.wait_until(self.due, stop):
            return False
        now = self.clock.now_ns()
        self.due += self.period_ns
        if self.due <= now:
            self.due = now + self.period_ns
        return True


def follow_clock(node: Node) -> None:
    """The planned node (``hetros_clock_<process>``) that moves its process' simulated clock to each
    time published on ``/clock``."""
    clock = node.graph.clock
    if not isinstance(clock, SimulatedClock):
        raise NodeError(f"{node.name} follows /clock, but its graph's clock is not simulated (use_sim_time)")

    def moved(message: Any) -> None:
        clock.set(int(message.clock.sec) * _NS + int(message.clock.nanosec))
    node.create_subscription(registry().get(CLOCK_TYPE), CLOCK_TOPIC, moved)
    node.spin()


class SimulatedTimer:
    """``create_timer`` against a simulated clock: due when the clock passes its time, run by the
    node's executor like any timer."""

    def __init__(self, clock: Clock, executor: Executor, period: float, callback: Callable[[], object]) -> None:
        self.period_ns = int(period * _NS)
        self.callback = callback
        self.cancelled = False
        self._clock = clock
        self._executor = executor
        self._lock = threading.Lock()
        self._due = clock.now_ns() + self.period_ns
        self._queued = False
        clock.on_advance(self._advanced)

    def _advanced(self) -> None:
        with self._lock:
            if self.cancelled or self._queued or self._clock.now_ns() < self._due:
                return
            self._queued = True
        self._executor.add_timer(time.monotonic(), self._fire)

    def _fire(self) -> float | None:
        with self._lock:
            self._queued = False
            now = self._clock.now_ns()
            if self.cancelled or now < self._due:
                return None
            self._due += self.period_ns
            if self._due <= now:
                self._due = now + self.period_ns
        self.callback()  # a clock that jumped several periods calls once, as a late wall timer does
        return None

    def cancel(self) -> None:
        with self._lock:
            if self.cancelled:
                return
            self.cancelled = True
        self._executor.entities -= 1
