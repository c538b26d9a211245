"""Same-process transport: the message object itself is handed over.

The publisher's message is frozen (read-only) and the very same object goes to
every subscriber's FIFO: no copy, no serialization, whatever the size.

A lifespan is the publishing endpoint's, as in DDS: each writer stamps what it delivers with the
moment it expires, so two publishers of one topic may keep their messages for different times.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from typing import Any

from .._errors import PublishTimeoutError, ShutdownError
from .._qos import QoS
from ._base import Reader, Wake, Writer
from ._seam import Endpoint, Transport, TransportContext


class Mailbox(Reader):
    """One subscriber's bounded FIFO, with the QoS's overflow rule."""

    def __init__(self, topic: str, owner: str, qos: QoS, wake: Wake) -> None:
        self.topic = topic
        self.owner = owner
        self.qos = qos
        self._wake = wake
        self._items: deque[Any] = deque()
        # when each item expires (its writer's lifespan), kept from the first item that does
        self._expires: deque[float] | None = None
        self._cond = threading.Condition()
        self._closed = False
        self.dropped = 0  # keep_last: items replaced by newer ones before the owner took them
        self.stalls = 0  # puts that waited for room (reliable keep_all), counted here, reported by the writers
        self.expired = 0  # items dropped unread for being older than the lifespan
        self.source: InprocTopic | None = None  # whose writers' liveliness this mailbox reports

    def put(self, item: Any, deadline: float, stop: threading.Event | None, expires: float = math.inf) -> None:
        with self._cond:
            if self._closed:
                return
            if len(self._items) >= self.qos.depth:
                if not self.qos.blocks_publisher:
                    self._items.popleft()
                    if self._expires is not None:
                        self._expires.popleft()
                    self.dropped += 1
                else:
                    self.stalls += 1
                    while len(self._items) >= self.qos.depth and not self._closed:
                        remaining = deadline - time.monotonic()
                        if stop is not None and stop.is_set():
                            raise ShutdownError(f"publishing on {self.topic} interrupted by shutdown")
                        if remaining <= 0:
                            raise PublishTimeoutError(
                                f"publishing on {self.topic}: subscriber {self.owner!r} kept its FIFO "
                                f"of depth {self.qos.depth} full for {self.qos.publish_timeout:g} s "
                                "(reliable + keep_all blocks the publisher); make the subscriber "
                                "faster, raise 'depth' or 'publish_timeout', or use keep_last"
                            )
                        self._cond.wait(min(remaining, 0.1))
                    if self._closed:
                        return
            if self._expires is None and expires != math.inf:
                self._expires = deque(math.inf for _ in self._items)
            self._items.append(item)
            if self._expires is not None:
                self._expires.append(expires)
        self._wake()

    def counters(self) -> dict[str, int]:
        return {"dropped": self.dropped}

    def try_take(self) -> Any | None:
        with self._cond:
            while self._items:
                item = self._items.popleft()
                self._cond.notify_all()
                if self._expires is None or time.monotonic() <= self._expires.popleft():
                    return item
                self.expired += 1
            return None

    def pending(self) -> bool:
        return bool(self._items)

    def has_room(self) -> bool:
        return not self.qos.blocks_publisher or self._closed or len(self._items) < self.qos.depth

    def liveliness(self) -> tuple[int, int] | None:
        return None if self.source is None else self.source.liveliness()

    def __len__(self) -> int:
        return len(self._items)

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()


class InprocTopic:
    """All subscribers of one topic inside this process, plus its transient_local history."""

    def __init__(self, name: str, qos: QoS, stop: threading.Event | None = None) -> None:
        self.name = name
        self.qos = qos
        self._stop = stop
        self._lock = threading.RLock()
        self._mailboxes: list[Mailbox] = []
        self._history: deque[tuple[Any, float]] = deque(maxlen=qos.depth)  # (item, when it expires)
        self._writers: list[InprocWriter] = []

    def open_reader(self, owner: str, wake: Wake, qos: QoS | None = None) -> Mailbox:
        mailbox = Mailbox(self.name, owner, qos or self.qos, wake)
        mailbox.source = self
        with self._lock:
            self._mailboxes.append(mailbox)
            if self.qos.keeps_history:
                for item, expires in self._history:  # a late joiner's history expires when it would have
                    mailbox.put(item, time.monotonic() + self.qos.publish_timeout, self._stop, expires)
        return mailbox

    def open_writer(self, lifespan: float | None = None) -> InprocWriter:
        writer = InprocWriter(self, lifespan)
        with self._lock:
            self._writers.append(writer)
        return writer

    def liveliness(self) -> tuple[int, int]:
        """In one process an ``automatic`` publisher is alive until it is closed, and a closed one is
        gone, counted neither way (as ROS 2 counts a deleted writer); a ``manual_by_topic`` one is alive
        while it asserted within ``lease_duration``."""
        now = time.monotonic()
        lease = self.qos.lease_duration
        with self._lock:
            writers = [writer for writer in self._writers if not writer.closed]
        alive = 0
        for writer in writers:
            if self.qos.liveliness == "manual_by_topic":
                if writer.asserted is None or (lease is not None and now - writer.asserted > lease):
                    continue
            alive += 1
        return alive, len(writers) - alive

    def stalls(self) -> int:
        with self._lock:
            return sum(mailbox.stalls for mailbox in self._mailboxes)

    def has_room(self) -> bool:
        with self._lock:
            return all(mailbox.has_room() for mailbox in self._mailboxes)

    def deliver(self, item: Any, lifespan: float | None = None) -> None:
        now = time.monotonic()
        deadline = now + self.qos.publish_timeout
        expires = math.inf if lifespan is None else now + lifespan
        with self._lock:
            if self.qos.keeps_history:
                self._history.append((item, expires))
            for mailbox in list(self._mailboxes):
                mailbox.put(item, deadline, self._stop, expires)


class InprocWriter(Writer):
    shares_objects = True  # the publisher's object goes into each subscriber's mailbox

    def __init__(self, topic: InprocTopic, lifespan: float | None) -> None:
        self._topic = topic
        self._lifespan = lifespan
        self.closed = False
        self.asserted: float | None = None  # when it last said it is alive (manual_by_topic)

    def write(self, message: Any) -> None:
        self._topic.deliver(message, self._lifespan)

    def has_room(self) -> bool:
        return self._topic.has_room()

    def counters(self) -> dict[str, int]:
        return {"stalls": self._topic.stalls()}

    def assert_liveliness(self) -> None:
        self.asserted = time.monotonic()

    def close(self) -> None:
        self.closed = True


class InprocTransport(Transport):
    """Edges inside one process: the publisher's object goes into each subscriber's mailbox."""

    kind = "inproc"

    def __init__(self, context: TransportContext) -> None:
        super().__init__(context)
        self._lock = threading.Lock()
        self._topics: dict[str, InprocTopic] = {}

    def topic(self, name: str, qos: QoS) -> InprocTopic:
        with self._lock:
            topic = self._topics.get(name)
            if topic is None:
                topic = self._topics[name] = InprocTopic(name, qos, self.context.stop)
            return topic

    def open_writer(self, endpoint: Endpoint) -> InprocWriter:
        return self.topic(endpoint.name, endpoint.qos).open_writer(endpoint.qos.lifespan)

    def open_reader(self, endpoint: Endpoint, wake: Wake) -> Mailbox:
        return self.topic(endpoint.name, endpoint.qos).open_reader(endpoint.node, wake)

    def close(self) -> None:
        with self._lock:
            self._topics.clear()
