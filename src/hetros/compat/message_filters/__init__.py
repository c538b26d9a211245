"""message_filters for rclpy and rospy nodes: filters that pass messages on through ``registerCallback``
(``SimpleFilter``), a topic as a filter (``Subscriber``), the last messages kept by time (``Cache``),
sets with one stamp per input (``TimeSynchronizer``) or stamps within a slop
(``ApproximateTimeSynchronizer``), and filters in series (``Chain``).

The synchronizers follow message_filters' Python algorithm step for step, so the sets they emit, and
their order, are the reference's (tests/unit/test_message_filters.py holds them against Debian's
python3-message-filters). Stamps are kept as integer nanoseconds whatever the ROS flavour; what a
method hands back is the node's flavour of time (rclpy's Time, or rospy.Time)."""

from __future__ import annotations

import itertools
import threading
from collections.abc import Callable, Iterable
from functools import reduce
from typing import Any

from ..._log import get_logger
from ..tf2_py import time_of, to_ns

log = get_logger("message_filters")


def _now_ns() -> int:
    """The node's ROS time (rclpy's ROSClock; /clock's under use_sim_time)."""
    from ..rclpy.clock import ROSClock

    return ROSClock().now_ns()


def _stamp_ns(msg: Any, allow_headerless: bool, what: str) -> int | None:
    """A message's header stamp in ns; a headerless message's arrival time where that is allowed, else
    None (with message_filters' warning)."""
    header = getattr(msg, "header", None)
    stamp = getattr(header, "stamp", None) if header is not None else None
    if stamp is None:
        if not allow_headerless:
            log.warning("%s: cannot use message filters with non-stamped messages; use allow_headerless=True to "
                        "stamp them with the time they arrive", what)
            return None
        return _now_ns()
    return to_ns(stamp)


class SimpleFilter:
    """A filter's output: callbacks registered with extra arguments, called with each message set."""

    def __init__(self) -> None:
        self.callbacks: dict[int, tuple[Callable[..., Any], tuple[Any, ...]]] = {}
        self._next_id = 0

    def registerCallback(self, cb: Callable[..., Any], *args: Any) -> int:
        """``cb(*messages, *args)`` for every output; an id for ``unregisterCallback``."""
        conn = self._next_id
        self._next_id += 1
        self.callbacks[conn] = (cb, args)
        return conn

    def unregisterCallback(self, conn: int) -> None:
        self.callbacks.pop(conn, None)

    def signalMessage(self, *msg: Any) -> None:
        for cb, args in list(self.callbacks.values()):
            cb(*(msg + args))


class Subscriber(SimpleFilter):
    """A topic as a filter: ROS 2's ``Subscriber(node, msg_type, topic, qos_profile=10)`` or ROS 1's
    ``Subscriber(topic, msg_type)`` (on the rospy node)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__()
        if args and isinstance(args[0], str):  # rospy: Subscriber(name, data_class, ...)
            from ..rospy import Subscriber as Ros1Subscriber

            self.topic = args[0]
            self.sub = Ros1Subscriber(args[0], args[1], self.callback, *args[2:], **kwargs)
            return
        node, msg_type, topic = args[:3]
        qos = args[3] if len(args) > 3 else kwargs.pop("qos_profile", 10)
        self.node, self.topic = node, topic
        self.sub = node.create_subscription(msg_type, topic, self.callback, qos, **kwargs)

    def callback(self, msg: Any) -> None:
        self.signalMessage(msg)

    def getTopic(self) -> str:
        return str(getattr(self.sub, "topic_name", None) or getattr(self.sub, "name", None) or self.topic)

    def unregister(self) -> None:
        if hasattr(self.sub, "unregister"):
            self.sub.unregister()
        elif getattr(self, "node", None) is not None:
            self.node.destroy_subscription(self.sub)

    def __getattr__(self, key: str) -> Any:
        if key == "sub":
            raise AttributeError(key)
        return getattr(self.sub, key)


class Cache(SimpleFilter):
    """The last ``cache_size`` messages, with their stamps, looked up by time."""

    def __init__(self, f: SimpleFilter | None = None, cache_size: int = 1, allow_headerless: bool = False) -> None:
        super().__init__()
        self.cache_size = cache_size
        self.allow_headerless = allow_headerless
        self.cache_msgs: list[Any] = []
        self.cache_times: list[int] = []
        self.lock = threading.Lock()
        if f is not None:
            self.connectInput(f)

    def connectInput(self, f: SimpleFilter) -> None:
        self.incoming_connection = f.registerCallback(self.add)

    def add(self, msg: Any) -> None:
        stamp = _stamp_ns(msg, self.allow_headerless, "Cache")
        if stamp is None:
            return
        with self.lock:
            self.cache_msgs.append(msg)
            self.cache_times.append(stamp)
            while len(self.cache_msgs) > self.cache_size:
                del self.cache_msgs[0], self.cache_times[0]
        self.signalMessage(msg)

    def getInterval(self, from_stamp: Any, to_stamp: Any) -> list[Any]:
        """The messages stamped from ``from_stamp`` to ``to_stamp``, both included."""
        low, high = to_ns(from_stamp), to_ns(to_stamp)
        with self.lock:
            return [m for m, t in zip(self.cache_msgs, self.cache_times, strict=True) if low <= t <= high]

    def getElemAfterTime(self, stamp: Any) -> Any:
        """The first message stamped at or after ``stamp`` (None if none)."""
        at = to_ns(stamp)
        with self.lock:
            return next((m for m, t in zip(self.cache_msgs, self.cache_times, strict=True) if t >= at), None)

    def getElemBeforeTime(self, stamp: Any) -> Any:
        """The last message stamped at or before ``stamp`` (None if none)."""
        at = to_ns(stamp)
        with self.lock:
            before = [m for m, t in zip(self.cache_msgs, self.cache_times, strict=True) if t <= at]
        return before[-1] if before else None

    def getLatestTime(self) -> Any:
        with self.lock:
            return time_of(self.cache_times[-1]) if self.cache_times else None

    getLastestTime = getLatestTime  # ROS 2's spelling

    def getOldestTime(self) -> Any:
        with self.lock:
            return time_of(self.cache_times[0]) if self.cache_times else None

    def getLast(self) -> Any:
        with self.lock:
            return self.cache_msgs[-1] if self.cache_msgs else None


class _Synchronizer(SimpleFilter):
    def __init__(self, fs: Iterable[SimpleFilter], queue_size: int) -> None:
        super().__init__()
        self.queue_size = queue_size
        self.lock = threading.Lock()
        self.queues: list[dict[int, Any]] = []
        self.input_connections: list[int] = []
        self.connectInput(fs)

    def connectInput(self, fs: Iterable[SimpleFilter]) -> None:
        filters = list(fs)
        self.queues = [{} for _ in filters]
        self.input_connections = [f.registerCallback(self.add, queue, index)
                                  for index, (f, queue) in enumerate(zip(filters, self.queues, strict=True))]

    def _keep(self, queue: dict[int, Any], stamp: int, msg: Any) -> None:
        queue[stamp] = msg
        while len(queue) > self.queue_size:
            del queue[min(queue)]

    def add(self, msg: Any, my_queue: dict[int, Any], my_queue_index: int | None = None) -> None:
        raise NotImplementedError


class TimeSynchronizer(_Synchronizer):
    """Sets of messages with one stamp on every input, emitted in stamp order."""

    def add(self, msg: Any, my_queue: dict[int, Any], my_queue_index: int | None = None) -> None:
        stamp = _stamp_ns(msg, False, "TimeSynchronizer")
        if stamp is None:
            return
        with self.lock:
            self._keep(my_queue, stamp, msg)
            common = reduce(set.intersection, [set(queue) for queue in self.queues])
            ready = []
            for t in sorted(common):
                ready.append([queue[t] for queue in self.queues])
                for queue in self.queues:
                    del queue[t]
        for msgs in ready:
            self.signalMessage(*msgs)


class ApproximateTimeSynchronizer(_Synchronizer):
    """Sets of messages whose stamps lie within ``slop`` seconds of each other: on each arrival, the other
    inputs' stamps within the slop of the new one are tried nearest first, and the first combination
    spanning less than the slop is emitted and taken out of the queues. When the node's clock goes back
    (a bag played again under use_sim_time) the queues are cleared; ``reset`` clears an input's queue
    when its own arrivals go back in time."""

    def __init__(self, fs: Iterable[SimpleFilter], queue_size: int, slop: float, allow_headerless: bool = False,
                 reset: bool = False) -> None:
        super().__init__(fs, queue_size)
        self.slop = to_ns(slop) if not isinstance(slop, int | float) else round(slop * 1e9)
        self.allow_headerless = allow_headerless
        self.reset = reset
        self.last_added = -1
        self.latest = [-1] * len(self.queues)  # each input's last arrival, on the node's clock (reset)

    def add(self, msg: Any, my_queue: dict[int, Any], my_queue_index: int | None = None) -> None:
        stamp = _stamp_ns(msg, self.allow_headerless, "ApproximateTimeSynchronizer")
        if stamp is None:
            return
        emitted: list[Any] | None = None
        with self.lock:
            now = _now_ns()
            if self.reset and my_queue_index is not None and now < self.latest[my_queue_index]:
                my_queue.clear()  # this input's clock went back (a bag played again)
            if my_queue_index is not None:
                self.latest[my_queue_index] = now
            my_queue[stamp] = msg
            if now < self.last_added:  # the clock went back: what the queues hold belongs to another time
                for queue in self.queues:
                    queue.clear()
            self.last_added = now
            while len(my_queue) > self.queue_size:
                del my_queue[min(my_queue)]
            others = self.queues if my_queue_index is None else \
                self.queues[:my_queue_index] + self.queues[my_queue_index + 1:]
            candidates: list[list[int]] = []
            for queue in others:
                near = [(s, abs(s - stamp)) for s in queue if abs(s - stamp) <= self.slop]
                if not near:
                    return
                near.sort(key=lambda pair: pair[1])
                candidates.append([s for s, _delta in near])
            for combination in itertools.product(*candidates):
                stamps = list(combination)
                if my_queue_index is not None:
                    stamps.insert(my_queue_index, stamp)
                pairs = list(zip(self.queues, stamps, strict=True))
                if max(stamps) - min(stamps) < self.slop and all(t in queue for queue, t in pairs):
                    emitted = [queue[t] for queue, t in pairs]
                    for queue, t in pairs:
                        del queue[t]
                    break
        if emitted is not None:
            self.signalMessage(*emitted)


class Chain(SimpleFilter):
    """Filters in series: the input goes into the first, each one's output into the next, and the last
    one's output is the chain's."""

    def __init__(self, filters: Iterable[SimpleFilter] = ()) -> None:
        super().__init__()
        self._filters: list[SimpleFilter] = []
        self._last_connection: tuple[SimpleFilter, int] | None = None
        for f in filters:
            self.addFilter(f)

    def addFilter(self, f: SimpleFilter) -> int:
        if self._filters:
            connect = getattr(f, "connectInput", None)
            if connect is None:
                raise TypeError(f"a filter of a chain after the first must take an input (connectInput), not {f!r}")
            connect(self._filters[-1])
        if self._last_connection is not None:
            previous, conn = self._last_connection
            previous.unregisterCallback(conn)
        self._filters.append(f)
        self._last_connection = (f, f.registerCallback(self.signalMessage))
        return len(self._filters) - 1

    def getFilter(self, index: int) -> SimpleFilter:
        return self._filters[index]

    def connectInput(self, f: SimpleFilter) -> None:
        if not self._filters:
            raise TypeError("a chain takes its input into its first filter: add one first")
        self._filters[0].connectInput(f)  # type: ignore[attr-defined]

    def add(self, msg: Any) -> None:
        """Feed the chain's first filter directly."""
        first = self._filters[0]
        add = getattr(first, "add", None)
        if add is not None:
            add(msg)
        else:
            first.signalMessage(msg)


__all__ = ["ApproximateTimeSynchronizer", "Cache", "Chain", "SimpleFilter", "Subscriber", "TimeSynchronizer"]
