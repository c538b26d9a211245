"""Taps: where a look from outside (``hetros topic echo``, ``hz``, ``record``, ``top``) meets a topic.

Every topic published in a process has one :class:`TapPoint` there, made with the process'
first publisher of it. The publisher counts what it sends (the figures ``hetros top`` shows,
kept whether anyone looks or not) and offers each message to the point's sinks only when
there are any: an idle tap is one attribute test per publish.

A sink never holds a publisher back. It queues a bounded number of messages for the thread
that sends them out; when that thread falls behind, a message is dropped and counted, and the
counts travel with the next message sent. What a sink keeps is taken while the publisher
waits, before the message is written, because a loan's arrays leave with a shared-memory send:
a sink that wants bytes (echo, record) encodes the message; one that wants only times and
sizes (hz, bw, delay) measures its encoded size and reads its header stamp, which costs a few
field reads and no copy.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from .._errors import InspectError
from ..transport import MessageCodec

# messages a sink keeps for its sender: meta records are small, encoded messages may be images
META_DEPTH = 4096
DATA_DEPTH = 64
DATA_BYTES = 64 << 20


# a look's rate cap: 0 (none), else within these (a cap of 1e-320 Hz once overflowed in publish())
MIN_RATE, MAX_RATE = 1e-3, 1e6


def check_rate(rate: object, what: str) -> float:
    """A look's rate cap, checked before it can reach a publisher."""
    if isinstance(rate, bool) or not isinstance(rate, int | float) or not (
            rate == 0 or MIN_RATE <= rate <= MAX_RATE):
        raise InspectError(f"{what} must be 0 (no cap) or a number of Hz in {MIN_RATE:g}..{MAX_RATE:g}, not {rate!r}")
    return float(rate)


class TapSink:
    """One look at one topic: a bounded queue between the publisher and the sender."""

    def __init__(self, codec: MessageCodec, *, data: bool, max_rate: float = 0.0) -> None:
        check_rate(max_rate, "a look's max_rate")
        self.codec = codec
        self.data = data  # False: times and sizes only
        self.max_rate = max_rate
        self.dropped = 0
        # appended by the publisher, taken by the sender (a deque's ends are thread-safe); the byte
        # counts are kept one per side so that neither thread writes the other's
        self._queue: deque[tuple[int, Any]] = deque()
        self._added_bytes = 0
        self._taken_bytes = 0
        # buffers the sender has finished with, encoded into again: a camera's frames are all one size,
        # and a fresh megabyte costs more in page faults than its encoding
        self._spare: deque[bytearray] = deque(maxlen=4)
        self._nonempty = threading.Event()
        self._next_allowed = 0
        self.closed = False

    def offer(self, message: Any) -> None:
        now = time.time_ns()
        if self.max_rate and now < self._next_allowed:
            return  # a rate cap (a live view) thins the stream; it is not a loss
        queue = self._queue
        if not self.data:
            if len(queue) >= META_DEPTH:
                self.dropped += 1
                return
            item: Any = (self.codec.size(message), header_stamp(message))
        else:
            if len(queue) >= DATA_DEPTH or self._added_bytes - self._taken_bytes >= DATA_BYTES:
                self.dropped += 1
                return
            item = self._encode(message)
            self._added_bytes += len(item)
        if self.max_rate:
            self._next_allowed = now + int(1e9 / self.max_rate)
        queue.append((now, item))
        if not self._nonempty.is_set():
            self._nonempty.set()

    def _encode(self, message: Any) -> bytearray:
        size = self.codec.size(message)
        spare = self._spare
        buffer = spare.popleft() if spare and len(spare[0]) == size else bytearray(size)
        self.codec.encode_into(message, memoryview(buffer))
        return buffer

    def give_back(self, buffer: bytearray) -> None:
        """The sender is done with an encoded message's buffer: the next one may reuse it."""
        self._spare.append(buffer)

    def take(self, timeout: float) -> tuple[int, Any] | None:
        """The oldest queued (wall time in ns, size and stamp or encoded bytes), or None after ``timeout``."""
        queue = self._queue
        if not queue:
            self._nonempty.clear()
            if not queue and not self.closed:  # the publisher may have appended between the test and the clear
                self._nonempty.wait(timeout)
            if not queue:
                return None
        stamp, item = queue.popleft()
        if self.data:
            self._taken_bytes += len(item)
        return stamp, item

    def close(self) -> None:
        self.closed = True
        self._nonempty.set()


class TapPoint:
    """A topic as this process publishes it: counters kept always, sinks attached on demand."""

    __slots__ = ("_history", "_lock", "published", "remembers", "sinks", "topic", "typename")

    def __init__(self, topic: str, typename: str, history: int = 0) -> None:
        self.topic = topic
        self.typename = typename
        self.published = 0  # messages this process' publishers sent on the topic
        self.sinks: tuple[TapSink, ...] = ()
        self._lock = threading.Lock()
        # a transient_local topic's last messages, which a look that attaches late gets first (as a late
        # subscriber would: `topic echo /tf_static`, `tf frames`)
        self._history: deque[Any] | None = deque(maxlen=history) if history else None
        self.remembers = self._history is not None  # offered every message, looked at or not

    def offer(self, message: Any) -> None:
        # a loaned message's arrays leave with its send: only a look attached now may see it
        if self._history is not None and getattr(message, "_hetros_loan", None) is None:
            with self._lock:
                self._history.append(message)
        for sink in self.sinks:
            sink.offer(message)

    def attach(self, sink: TapSink) -> None:
        with self._lock:
            for message in self._history or ():
                sink.offer(message)
            self.sinks = (*self.sinks, sink)

    def detach(self, sink: TapSink) -> None:
        with self._lock:
            self.sinks = tuple(s for s in self.sinks if s is not sink)
        sink.close()


def header_stamp(message: Any) -> int | None:
    """The message's ``header.stamp`` in nanoseconds, or None when it has none."""
    stamp = getattr(getattr(message, "header", None), "stamp", None)
    if stamp is None or not hasattr(stamp, "nanosec"):
        return None
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def taking_tap(take: Callable[[], Any], point: TapPoint) -> Callable[[], Any]:
    """A subscription's take function that also offers what it takes to ``point``: the tap of a
    topic whose publisher is outside hetros (a ROS 1 or ROS 2 peer), swapped in only while tapped."""

    def take_and_offer() -> Any:
        message = take()
        if message is not None:
            point.published += 1
            if point.sinks:
                point.offer(message)
        return message
    return take_and_offer
