"""QoS events a node hears about: a missed deadline, a publisher's liveliness lost or regained.

Deadlines are kept here, above the transports, so they mean the same on every edge: a
subscription notes when it takes a message, a publisher when it publishes, and a timer in
the node's executor counts each ``deadline`` period that passes without one. The node's
callback (``on_deadline_missed``) runs in the node's executor like any other callback, as
in rclpy; without one, the miss is logged (rate-limited). A node that never spins still
has its misses counted when the next message is taken or published.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .._log import get_logger
from ..transport import Reader

if TYPE_CHECKING:
    from ._node import Node

log = get_logger("hetros.qos")


@dataclass
class DeadlineMissedStatus:
    """As ROS 2's: misses so far, and since the last report."""

    total_count: int = 0
    total_count_change: int = 0


@dataclass
class LivelinessChangedStatus:
    """As ROS 2's: publishers alive now and not alive, and the change since the last report."""

    alive_count: int = 0
    not_alive_count: int = 0
    alive_count_change: int = 0
    not_alive_count_change: int = 0


@dataclass
class MessageLostStatus:
    """As ROS 2's: messages this subscription lost (keep_last overwrote them before it took them, a
    best_effort transport dropped them), in all and since the last report."""

    total_count: int = 0
    total_count_change: int = 0


@dataclass
class LivelinessLostStatus:
    """As ROS 2's: the times this publisher let its lease pass without asserting its liveliness, in all
    and since the last report."""

    total_count: int = 0
    total_count_change: int = 0


class LivelinessLostWatch:
    """Counts the leases a ``manual_by_topic`` publisher let pass without publishing or calling
    ``assert_liveliness`` (each silence once, as ROS 2 counts them), looked at every half lease."""

    def __init__(self, node: Node, lease: float, callback: Callable[[LivelinessLostStatus], object]) -> None:
        self.node = node
        self.lease = lease
        self.callback = callback
        self.status = LivelinessLostStatus()
        self.asserted = time.monotonic()
        self._lost = False
        self._stopped = False
        node.executor.add_timer(self.asserted + lease / 2, self._check)

    def seen(self) -> None:
        self.asserted = time.monotonic()
        self._lost = False

    def _check(self) -> float | None:
        if self._stopped:
            return None
        now = time.monotonic()
        if not self._lost and now - self.asserted > self.lease:
            self._lost = True
            self.status.total_count += 1
            self.status.total_count_change = 1
            self.callback(self.status)
        return now + self.lease / 2

    def stop(self) -> None:
        self._stopped = True


class DeadlineWatch:
    """Counts the ``deadline`` periods of one endpoint that passed without a message."""

    def __init__(self, node: Node, what: str, deadline: float,
                 callback: Callable[[DeadlineMissedStatus], object] | None) -> None:
        self.node = node
        self.what = what
        self.deadline = deadline
        self.callback = callback
        self.status = DeadlineMissedStatus()
        self._since = time.monotonic()
        self._counted = 0  # periods of the current silence already counted
        self._stopped = False
        node.executor.add_timer(self._since + deadline, self._check)

    def seen(self) -> None:
        """A message was taken or published now: count the silence before it, then start anew."""
        now = time.monotonic()
        self._count(now)
        self._since, self._counted = now, 0

    def _check(self) -> float | None:
        if self._stopped:
            return None
        now = time.monotonic()
        self._count(now)
        # due again when the next period of this silence ends
        return self._since + (self._counted + 1) * self.deadline

    def _count(self, now: float) -> None:
        periods = int((now - self._since) / self.deadline)
        new = periods - self._counted
        if new <= 0:
            return
        self._counted = periods
        self.status.total_count += new
        self.status.total_count_change = new
        if self.callback is not None:
            self.callback(self.status)
        else:
            log.warning("%s: deadline of %g s missed %d time(s) (%d in all); pass on_deadline_missed to "
                        "handle it", self.what, self.deadline, new, self.status.total_count)

    def stop(self) -> None:
        self._stopped = True


class LivelinessWatch:
    """Reports when the publishers a subscription hears from become alive or not alive.

    The transports tell who is alive (``Reader.liveliness``): a process that ended, or a
    ``manual_by_topic`` publisher silent past ``lease_duration``; this looks every half
    lease (every half second without one) from the node's executor.
    """

    def __init__(self, node: Node, what: str, reader: Reader, lease: float | None,
                 callback: Callable[[LivelinessChangedStatus], object] | None) -> None:
        self.node = node
        self.what = what
        self.reader = reader
        self.callback = callback
        self.status = LivelinessChangedStatus()
        self.period = (lease or 1.0) / 2
        self._stopped = False
        node.executor.add_timer(time.monotonic() + self.period, self._check)

    def _check(self) -> float | None:
        if self._stopped:
            return None
        counts = self.reader.liveliness()
        if counts is not None and counts != (self.status.alive_count, self.status.not_alive_count):
            alive, gone = counts
            status = self.status
            status.alive_count_change, status.not_alive_count_change = alive - status.alive_count, \
                gone - status.not_alive_count
            status.alive_count, status.not_alive_count = alive, gone
            if self.callback is not None:
                self.callback(status)
            elif status.not_alive_count_change > 0:
                log.warning("%s: %d publisher(s) lost liveliness (%d alive)", self.what,
                            status.not_alive_count_change, alive)
        return time.monotonic() + self.period

    def stop(self) -> None:
        self._stopped = True


class MessageLostWatch:
    """Reports the messages a subscription lost, from its reader's ``dropped`` and ``expired`` counters,
    looked at ten times a second from the node's executor (only while someone listens: the callback)."""

    PERIOD = 0.1

    def __init__(self, node: Node, reader: Reader, callback: Callable[[MessageLostStatus], object]) -> None:
        self.reader = reader
        self.callback = callback
        self.status = MessageLostStatus()
        self._stopped = False
        node.executor.add_timer(time.monotonic() + self.PERIOD, self._check)

    def _check(self) -> float | None:
        if self._stopped:
            return None
        counters = self.reader.counters()
        lost = counters.get("dropped", 0) + counters.get("expired", 0)
        if lost > self.status.total_count:
            self.status.total_count_change = lost - self.status.total_count
            self.status.total_count = lost
            self.callback(self.status)
        return time.monotonic() + self.PERIOD

    def stop(self) -> None:
        self._stopped = True


class WatchedReader(Reader):
    """A subscription's reader whose every message counts as seen by its deadline watch."""

    def __init__(self, inner: Reader, watch: DeadlineWatch) -> None:
        self.inner = inner
        self.watch = watch

    def try_take(self) -> Any | None:
        message = self.inner.try_take()
        if message is not None:
            self.watch.seen()
        return message

    def pending(self) -> bool:
        return self.inner.pending()

    def liveliness(self) -> tuple[int, int] | None:
        return self.inner.liveliness()

    def counters(self) -> dict[str, int]:
        return self.inner.counters()

    def close(self) -> None:
        self.watch.stop()
        self.inner.close()


def watch_deadline(node: Node, what: str, deadline: float | None,
                   callback: Callable[[DeadlineMissedStatus], object] | None) -> DeadlineWatch | None:
    return None if deadline is None else DeadlineWatch(node, what, deadline, callback)

