"""The node API's entities: publishers, subscriptions, timers, services and clients.

Each is what rclpy's is, with one meaning on every mapping: it reads and writes through the
graph's endpoints and never names a transport. ``Node`` (in ``_node``) makes them.
"""

from __future__ import annotations

import itertools
import os
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from typing import TYPE_CHECKING, Any, Generic, TypeVar, cast

from .._errors import (
    ServiceTimeoutError,
    ShutdownError,
    TakeTimeoutError,
    TopicTypeError,
)
from ..msg import Message, ServiceKind, service_type
from ..msg import copy as copy_message
from ..plan import reply_channel, request_channel
from ..transport import Reader, Writer
from ._clock import check_period
from ._endpoints import EndpointWriter
from ._executor import AdaptiveSpin
from ._matched import MatchedWatch
from ._qos_events import (
    DeadlineWatch,
    LivelinessLostWatch,
    LivelinessWatch,
    MessageLostWatch,
    WatchedReader,
)
from ._service_events import EventKind, ServiceEvents
from ._taps import taking_tap

if TYPE_CHECKING:
    from ._node import Node

M = TypeVar("M", bound=Message)
_MISSING: Any = object()

# set (to 1) by ``hetros advise`` in the launches it profiles: node times then also count the CPU time
# the node's thread spent (its own work, apart from waiting for a shared core or the GIL), and each
# publish counts which input the node was handling when it sent (the causal edges of the advisor's model)
PROFILE_VARIABLE = "HETROS_PROFILE"
PROFILING = os.environ.get(PROFILE_VARIABLE, "") not in ("", "0")



def _nothing() -> None:
    """The take of a subscription with no reader (closed, or not attached yet)."""
    return None


def typename_of(msg_type: type[Message]) -> str:
    name = getattr(msg_type, "__msgtype__", "")
    if not name:
        raise TopicTypeError(f"message type must be a hetros message class, not {msg_type!r}")
    return str(name)


def check_type(value: object, expected: str, where: str) -> None:
    actual = getattr(value, "__msgtype__", None)
    if actual != expected:
        raise TopicTypeError(
            f"{where} carries {expected}, not {actual or type(value).__name__}; "
            f"construct a {expected.rsplit('/', 1)[-1]} (or fix the type in the project file)"
        )


class Publisher(Generic[M]):
    """Publishes on one topic.

    ``publish`` hands the message object over (it becomes read-only) but leaves your arrays
    yours: a writable array you own is copied once (into shared memory, or into a read-only
    copy for in-process subscribers). ``publish(message, keep=True)`` leaves the whole message
    yours, as rclpy and rospy do. ``loan`` gives arrays hetros owns, which travel without a copy.
    """

    def __init__(self, node: Node, msg_type: type[M], topic: str, writer: EndpointWriter) -> None:
        self.node = node
        self.msg_type = msg_type
        self.topic = topic
        self.typename = typename_of(msg_type)
        self._short = self.typename.rsplit("/", 1)[-1]
        self._writer = writer
        self._loans: dict[tuple[tuple[str, int], ...], Callable[[], M]] = {}
        self._last_sizes: dict[str, int] | None = None
        self._last_make: Callable[[], M] = msg_type
        self.deadline: DeadlineWatch | None = None  # the topic's QoS deadline, offered (``on_deadline_missed``)
        self.manual_liveliness = False  # each publish asserts liveliness (the topic's is manual_by_topic)
        self.liveliness_lost: LivelinessLostWatch | None = None  # its lapses, when someone listens
        self._closed = False
        self.matched: MatchedWatch | None = None  # its matched subscriptions, while it is open
        # the topic's tap in this process: counts what is sent; sinks only while someone looks
        self._tap = node.graph.tap_point(topic, self.typename)

    def publish(self, message: M, *, keep: bool = False) -> None:
        """Hand ``message`` to every subscriber; a field value its type cannot carry raises FieldValueError.

        ``keep``: the message stays yours, to change and publish again (rclpy's and rospy's rule). It
        is copied only where a subscriber in this process would get the object itself; transports
        between processes serialize it as it is, so a large message costs no copy of its own.
        """
        if getattr(message, "__msgtype__", None) != self.typename:
            check_type(message, self.typename, f"topic {self.topic}")
        message._hetros_validate(message, self._short)
        write = self._writer.write
        if keep:
            if self._writer.shares_objects or getattr(message, "_hetros_loan", None) is not None:
                message = copy_message(message)
            else:
                write = self._writer.write_kept
        tap = self._tap
        tap.published += 1
        if tap.sinks or tap.remembers:  # before the write: a loan's arrays leave with a shared-memory send
            tap.offer(message)
        write(message)
        if self.deadline is not None:
            self.deadline.seen()
        if self.manual_liveliness:
            self.assert_liveliness()
        if PROFILING:
            self.node.count_publish(self.topic)

    def has_room(self) -> bool:
        """Whether ``publish`` now would go through without waiting for a reliable subscriber's room (a
        keep_all subscriber whose FIFO is full). For a node that serves several streams at once and must
        not let one full subscriber stop the others: ask, and publish later what has no room yet."""
        return self._writer.has_room()

    def counters(self) -> dict[str, int]:
        """``stalls``: the sends that waited for a reliable subscriber's room (``hetros top``)."""
        return self._writer.counters()

    def assert_liveliness(self) -> None:
        """Say this publisher is alive without publishing (``manual_by_topic`` liveliness)."""
        self._writer.assert_liveliness()
        if self.liveliness_lost is not None:
            self.liveliness_lost.seen()

    def loan(self, **sizes: int) -> M:
        """A message to fill in place and publish without a copy.

        Give the length of each variable-length primitive array to fill (``data=640*480*3``);
        fixed-size arrays are placed automatically; a nested array is named with ``__``
        (``header__...``). When a subscriber is in another process and the arrays are large
        (over 64 KiB), they live in the shared-memory slot that is then sent as it is;
        smaller ones live in memory hetros owns and are copied once into the slot. After
        ``publish`` the loaned message is handed over: its arrays are no longer yours.
        """
        if sizes == self._last_sizes:  # the same lengths as last time, the common loop: one comparison
            return self._last_make()
        make = self._loans.get(tuple(sizes.items()))
        if make is None:
            make = cast("Callable[[], M]", self._writer.loan_maker(self.msg_type, sizes))
            if len(self._loans) > 64:  # lengths that keep changing must not grow the cache forever
                self._loans.clear()
            self._loans[tuple(sizes.items())] = make
        self._last_sizes, self._last_make = sizes, make
        return make()

    def sends_in_place(self, message: M) -> bool:
        """Whether publishing ``message`` (a loan) sends its shared-memory slot as it is: no copy of its arrays."""
        return self._writer.sends_in_place(message)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        if self.deadline is not None:
            self.deadline.stop()
        if self.liveliness_lost is not None:
            self.liveliness_lost.stop()
        if self.matched is not None:
            self.node.graph.matches.left(self.topic, "publish", self.matched)
            self.matched = None
        self._writer.close()


class HandlingStats:
    """How long a node spends on each message of one endpoint (the "node time" of the papers' tables).

    For callbacks and service handlers it is the handler's duration; for ``take`` loops,
    the time from one ``take`` returning to the next ``take`` call. The last
    ``RECENT`` durations are kept for ``hetros top``'s percentiles.
    """

    __slots__ = ("count", "cpu_count", "cpu_recent", "cpu_total", "recent", "total", "total_sq")
    RECENT = 256
    # 0 %, 5 %, ..., 95 %, 99 %, 100 %: the shape the advisor's model samples from (the tail apart, so
    # that one slow first message does not stand for the top 5 %)
    POINTS = (*(k / 20 for k in range(20)), 0.99, 1.0)

    def __init__(self) -> None:
        self.count = 0
        self.total = 0.0
        self.total_sq = 0.0
        self.recent = [0.0] * self.RECENT
        # the thread's CPU time per message, counted only while profiling (``HETROS_PROFILE``)
        self.cpu_count = 0
        self.cpu_total = 0.0
        self.cpu_recent = [0.0] * self.RECENT

    def add(self, seconds: float) -> None:
        self.recent[self.count % self.RECENT] = seconds
        self.count += 1
        self.total += seconds
        self.total_sq += seconds * seconds

    def add_cpu(self, seconds: float) -> None:
        self.cpu_recent[self.cpu_count % self.RECENT] = seconds
        self.cpu_count += 1
        self.cpu_total += seconds

    def summary(self) -> tuple[int, float, float]:
        """(count, mean ms, std ms)."""
        if not self.count:
            return 0, 0.0, 0.0
        mean = self.total / self.count
        return self.count, mean * 1000.0, max(self.total_sq / self.count - mean * mean, 0.0) ** 0.5 * 1000.0

    def snapshot(self) -> dict[str, float]:
        """Count, total seconds, and the 50th and 99th percentile of the recent durations."""
        count = self.count
        recent = sorted(self.recent[:min(count, self.RECENT)])
        if not recent:
            return {"count": 0, "total_s": 0.0, "p50_s": 0.0, "p99_s": 0.0}
        found: dict[str, Any] = {"count": count, "total_s": self.total, "p50_s": recent[len(recent) // 2],
                                 "p99_s": recent[min(len(recent) - 1, int(len(recent) * 0.99))],
                                 "quantiles_s": _quantiles(recent, self.POINTS)}
        if self.cpu_count:
            cpu = sorted(self.cpu_recent[:min(self.cpu_count, self.RECENT)])
            found.update(cpu_count=self.cpu_count, cpu_total_s=self.cpu_total,
                         cpu_quantiles_s=_quantiles(cpu, self.POINTS))
        return found


def _quantiles(ordered: list[float], points: tuple[float, ...]) -> list[float]:
    """The quantiles of ``ordered`` (sorted, not empty) at ``points`` (fractions, 0 to 1)."""
    last = len(ordered) - 1
    return [ordered[round(last * point)] for point in points]


class Subscription(Generic[M]):
    """Receives from one topic: by callback (run by the node's executor) or by ``take``."""

    def __init__(self, node: Node, msg_type: type[M], topic: str,
                 callback: Callable[[M], object] | None) -> None:
        self.node = node
        self.msg_type = msg_type
        self.topic = topic
        self.typename = typename_of(msg_type)
        self.callback = callback
        self._reader: Reader | None = None
        # the reader's take function (``Reader.taker``): called once per message
        self._take: Callable[[], M | None] = _nothing
        self.stats = HandlingStats()
        self._spin = AdaptiveSpin()
        self._polled_one = False  # try_take returned a message (a polling node counts no handling time)
        self.liveliness: LivelinessWatch | None = None  # set when its publishers' liveliness is watched
        self.message_lost: MessageLostWatch | None = None  # set when someone listens for lost messages
        self.matched: MatchedWatch | None = None  # its matched publishers, while it is open
        self._injected: deque[M] = deque()
        self.injected_handled_at = 0  # see inject
        self._inject_lock = threading.Lock()
        self._plain_take: Callable[[], M | None] | None = None  # the take that injection stands in front of
        self._heard_take: Callable[[], M | None] | None = None  # the take a deaf subscription drains (_deafen)
        self._watch: DeadlineWatch | None = None  # the topic's deadline, watched on this subscription's reader

    def _attach(self, reader: Reader) -> None:
        self._reader = reader
        self._take = reader.taker()
        point = self.node.graph.subscriber_tap(self.topic, self.typename)
        if point is not None:
            self._take = taking_tap(self._take, point)

    def _rebase(self, reader: Reader) -> None:
        """Take from ``reader`` from now on (its own branch, once the node subscribes to the topic again)."""
        self._attach(reader if self._watch is None else WatchedReader(reader, self._watch))

    def inject(self, message: M) -> int:
        """Deliver ``message`` to this subscription as if a publisher had sent it (``hetros topic pub``):
        a take function in front of the reader's, swapped in only while injected messages wait. The
        handled count (``stats.count``) at which this message has been handled."""
        with self._inject_lock:
            self.injected_handled_at = self.stats.count + len(self._injected) + 1
            self._injected.append(message)
            if self._plain_take is None:
                self._plain_take, self._take = self._take, self._take_injected
        self._on_wake()
        return self.injected_handled_at

    def _take_injected(self) -> M | None:
        with self._inject_lock:
            plain = self._plain_take
            assert plain is not None
            if self._injected:
                return self._injected.popleft()
            self._take, self._plain_take = plain, None
        return plain()

    def _deafen(self, deaf: bool) -> None:
        """Every publisher of this process offers less than this subscription requests (incompatible
        QoS): what they send is taken and dropped, as ROS 2 never delivers it; undone when one matches."""
        if deaf and self._heard_take is None:
            self._heard_take, self._take = self._take, self._take_deaf
        elif not deaf and self._heard_take is not None:
            self._take, self._heard_take = self._heard_take, None

    def _take_deaf(self) -> M | None:
        heard = self._heard_take
        while heard is not None and heard() is not None:
            pass
        return None

    def _on_wake(self) -> None:
        if self.callback is not None:
            self.node.executor.notify(self)
        else:
            self.node.executor.arrived()

    def dispatch(self) -> bool:
        if PROFILING:
            return self._profiled()
        message = self._take()
        if message is None:
            return False
        assert self.callback is not None
        start = time.perf_counter()
        self.callback(message)
        self.stats.add(time.perf_counter() - start)
        return True

    def _profiled(self) -> bool:
        """``dispatch`` while profiling: the CPU time counted includes taking (decoding) the message,
        which the receiving node's core pays for."""
        cpu = time.thread_time()
        message = self._take()
        if message is None:
            return False
        assert self.callback is not None
        node = self.node
        node.handling = self.topic
        start = time.perf_counter()
        try:
            self.callback(message)
        finally:
            node.handling = None
        self.stats.add(time.perf_counter() - start)
        self.stats.add_cpu(time.thread_time() - cpu)
        return True

    def pending(self) -> bool:
        reader = self._reader
        return reader is not None and reader.pending()

    def counters(self) -> dict[str, int]:
        """``dropped``: keep_last messages replaced by newer ones before this subscription took them."""
        reader = self._reader
        return {} if reader is None else reader.counters()

    def try_take(self) -> M | None:
        """The next message, or None when the FIFO is empty (never blocks)."""
        message: M | None = self._take()
        if message is not None:
            self._polled_one = True
        return message

    def received(self) -> bool:
        """Whether this subscription has delivered a message to its node, however the node takes them."""
        return self._polled_one or self.stats.count > 0 or self.node.taken_by is self

    def take(self, timeout: float | None = None) -> M:
        """Block for the next message; raise TakeTimeoutError, or ShutdownError on shutdown."""
        now = time.perf_counter()
        node = self.node
        working_on = node.taken_by
        if working_on is not None:
            # the node's time on the message it took last ends at its next take, on whichever
            # subscription: waiting for another topic is not time spent on this one's message
            working_on.stats.add(now - node.taken_at)
            if PROFILING:
                working_on.stats.add_cpu(time.thread_time() - node.taken_cpu)
            node.taken_by = None  # a take that times out or is interrupted starts no node time
        message: M | None = self._take()
        if message is None:
            message = self._wait_for_message(timeout)
        else:  # a message was already waiting: the common case of a busy loop, without the waiting machinery
            self._spin.arrived(now)
        node.taken_by, node.taken_at = self, time.perf_counter()
        if PROFILING:
            node.taken_cpu = time.thread_time()
            node.in_period = False
        return message

    def _wait_for_message(self, timeout: float | None) -> M:
        deadline = None if timeout is None else time.monotonic() + timeout
        stop = self.node.graph.stop
        executor = self.node.executor
        started = time.perf_counter()
        spin = self._spin.budget(started)
        if spin:
            spin_end = started + spin
            polls = 0
            executor.hot_spin(True)
            try:
                while (now := time.perf_counter()) < spin_end:
                    message = self._take()
                    if message is not None:
                        self._spin.arrived(now)
                        return message
                    polls += 1
                    if polls >= executor.yield_every:  # hands the GIL over (sleep(0) naps ~90 µs); see SPARSE_YIELD
                        polls = 0
                        os.sched_yield()
            finally:
                executor.hot_spin(False)
        while True:
            seen = executor.generation
            message = self._take()
            if message is not None:
                self._spin.arrived(time.perf_counter())
                return message
            if stop.is_set():
                raise ShutdownError(f"take on {self.topic} interrupted: the graph is shutting down")
            wait = None if deadline is None else deadline - time.monotonic()
            if wait is not None and wait <= 0:
                raise TakeTimeoutError(f"no message on {self.topic} within {timeout:g} s")
            executor.wait(seen, wait)

    def __iter__(self) -> Iterator[M]:
        """Messages until shutdown (the iterator form of a subscription)."""
        while True:
            try:
                yield self.take()
            except ShutdownError:
                return

    def close(self) -> None:
        """Stop receiving; a closed callback no longer keeps the node spinning after its function returns."""
        if self.liveliness is not None:
            self.liveliness.stop()
        if self.message_lost is not None:
            self.message_lost.stop()
        if self.matched is not None:
            self.node.graph.matches.left(self.topic, "subscribe", self.matched)
            self.matched = None
        if self._reader is not None:
            self._take = _nothing
            self._reader.close()
            self._reader = None
            if self.callback is not None:
                self.node.executor.entities -= 1
                self.node.executor.stop_polling(self)


class Timer:
    def __init__(self, node: Node, period: float, callback: Callable[[], object]) -> None:
        period = check_period(period, "a timer's period")
        self.period = period
        self.callback = callback
        self.cancelled = False
        self._node = node
        self._due = time.monotonic() + period
        node.executor.add_timer(self._due, self._fire)

    def _fire(self) -> float | None:
        if self.cancelled:
            return None
        self.callback()
        now = time.monotonic()
        self._due += self.period
        if self._due < now:
            self._due = now + self.period
        return None if self.cancelled else self._due

    def cancel(self) -> None:
        if not self.cancelled:
            self.cancelled = True
            self._node.executor.entities -= 1


class Replies:
    """The reply side of one service: a writer per calling client, opened on its first reply.
    Callable from any thread (an action's goals answer from theirs)."""

    def __init__(self, node: Node, service: str, response_type: str) -> None:
        self._node = node
        self._service = service
        self._response_type = response_type
        self._writers: dict[str, Writer] = {}
        self._lock = threading.Lock()

    def send(self, request_id: int, client: str, response: Any) -> None:
        with self._lock:
            writer = self._writers.get(client)
            if writer is None:
                writer = self._writers[client] = self._node.graph.open_writer(
                    reply_channel(self._service, client), self._node.name, self._response_type, envelope=True)
            writer.write((request_id, client, response))


class Service:
    """Serves one service: the handler takes a request and returns the response."""

    def __init__(self, node: Node, srv_type: ServiceKind, name: str,
                 handler: Callable[[Any], Any]) -> None:
        srv_type = service_type(srv_type)
        self.node = node
        self.srv_type = srv_type
        self.name = name
        self.handler = handler
        self._request_type = typename_of(srv_type.Request)
        self._response_type = typename_of(srv_type.Response)
        self._replies = Replies(node, name, self._response_type)
        self._closed = False
        self.stats = HandlingStats()
        self.events = ServiceEvents(node, name, srv_type)
        self._reader = node.graph.open_reader(
            request_channel(name), node.name, self._request_type,
            lambda: node.executor.notify(self), envelope=True,
        )

    def dispatch(self) -> bool:
        envelope = self._reader.try_take()
        if envelope is None:
            return False
        request_id, client, request = envelope
        self._replies.send(request_id, client, self.handle(request, request_id, client))
        return True

    def handle(self, request: Any, request_id: int | None = None, client: str = "") -> Any:
        """The handler's checked response to ``request`` (run in the node's executor); a call from the
        command line comes with no id, and gets one for its events."""
        sequence = self.events.next_sequence() if request_id is None else request_id
        self.events.offer(EventKind.REQUEST_RECEIVED, sequence, client, request)
        start = time.perf_counter()
        response = self.handler(request)
        self.stats.add(time.perf_counter() - start)
        check_type(response, self._response_type, f"the response of service {self.name}")
        response._hetros_validate(response, f"the response of {self.name}")
        self.events.offer(EventKind.RESPONSE_SENT, sequence, client, response)
        return response

    def pending(self) -> bool:
        return self._reader.pending()

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._reader.close()
            self.node.executor.entities -= 1


class Client:
    """Calls one service. Replies bypass the node's callback queue, so ``call`` is safe in callbacks."""

    def __init__(self, node: Node, srv_type: ServiceKind, name: str) -> None:
        srv_type = service_type(srv_type)
        self.node = node
        self.srv_type = srv_type
        self.name = name
        self._request_type = typename_of(srv_type.Request)
        self._response_type = typename_of(srv_type.Response)
        self._ids = itertools.count(1)
        self._pending: dict[int, Future[Any]] = {}
        self._lock = threading.Lock()
        self._reader: Reader | None = None
        self._writer = node.graph.open_writer(
            request_channel(name), node.name, self._request_type, envelope=True
        )
        self._reader = node.graph.open_reader(
            reply_channel(name, node.name), node.name, self._response_type, self._reply_arrived, envelope=True
        )
        self.events = ServiceEvents(node, name, srv_type)

    def _reply_arrived(self) -> None:
        self._on_reply()
        self.node.executor.arrived()

    def _on_reply(self) -> None:
        while self._reader is not None:
            with self._lock:
                envelope = self._reader.try_take()
                if envelope is None:
                    return
                future = self._pending.pop(envelope[0], None)
            if future is None or future.done():
                continue
            if isinstance(envelope[2], BaseException):  # a transport that could not deliver the call says why
                future.set_exception(envelope[2])
            else:
                self.events.offer(EventKind.RESPONSE_RECEIVED, envelope[0], self.node.name, envelope[2])
                future.set_result(envelope[2])

    def call_async(self, request: Any) -> Future[Any]:
        check_type(request, self._request_type, f"a request of service {self.name}")
        request._hetros_validate(request, f"the request to {self.name}")
        future: Future[Any] = Future()
        with self._lock:
            request_id = next(self._ids)
            self._pending[request_id] = future
        self.events.offer(EventKind.REQUEST_SENT, request_id, self.node.name, request)
        self._writer.write((request_id, self.node.name, request))
        return future

    def call(self, request: Any, timeout: float = 5.0) -> Any:
        """Send ``request`` and wait for the response; the caller's thread waits on the reply reader itself."""
        future = self.call_async(request)
        deadline = time.monotonic() + timeout
        executor = self.node.executor
        while True:
            seen = executor.generation
            self._on_reply()
            if future.done():
                return future.result()
            if self.node.graph.stop.is_set():
                reason = self.node.graph.stop_reason
                raise ShutdownError(f"call to {self.name} interrupted: the graph is shutting down"
                                    + (f" because {reason}" if reason else ""))
            left = deadline - time.monotonic()
            if left <= 0:
                with self._lock:
                    self._pending = {k: v for k, v in self._pending.items() if v is not future}
                raise ServiceTimeoutError(
                    f"service {self.name} did not reply within {timeout:g} s; is its server "
                    "node running (see `hetros graph`)?"
                )
            executor.wait(seen, left)

    def close(self) -> None:
        if self._reader is not None:
            self._reader.close()

