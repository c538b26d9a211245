"""Same-process transport: the message object itself is handed over.

The publisher's message is frozen (read-only) and the very same object goes to
every subscriber's FIFO: no copy, no serialization, whatever the size.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from typing import Any

from .._errors import PublishTimeoutError, ShutdownError
from ._base import Reader, Wake, Writer
from ._qos import QoS


class Mailbox(Reader):
    """One subscriber's bounded FIFO, with the QoS's overflow rule."""

    def __init__(self, topic: str, owner: str, qos: QoS, wake: Wake) -> None:
        self.topic = topic
        self.owner = owner
        self.qos = qos
        self._wake = wake
        self._items: deque[Any] = deque()
        self._cond = threading.Condition()
        self._closed = False
        self.dropped = 0

    def put(self, item: Any, deadline: float, stop: threading.Event | None) -> None:
        with self._cond:
            if self._closed:
                return
            if len(self._items) >= self.qos.depth:
                if not self.qos.blocks_publisher:
                    self._items.popleft()
                    self.dropped += 1
                else:
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
            self._items.append(item)
        self._wake()

    def try_take(self) -> Any | None:
        with self._cond:
            if not self._items:
                return None
            item = self._items.popleft()
            self._cond.notify_all()
            return item

    def pending(self) -> bool:
        return bool(self._items)

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
        self._history: deque[Any] = deque(maxlen=qos.depth)

    def open_reader(self, owner: str, wake: Wake, qos: QoS | None = None) -> Mailbox:
        mailbox = Mailbox(self.name, owner, qos or self.qos, wake)
        with self._lock:
            self._mailboxes.append(mailbox)
            if self.qos.keeps_history:
                for item in self._history:
                    mailbox.put(item, time.monotonic() + self.qos.publish_timeout, self._stop)
        return mailbox

    def open_writer(self) -> InprocWriter:
        return InprocWriter(self)

    def deliver(self, item: Any) -> None:
        deadline = time.monotonic() + self.qos.publish_timeout
        with self._lock:
            if self.qos.keeps_history:
                self._history.append(item)
            for mailbox in list(self._mailboxes):
                mailbox.put(item, deadline, self._stop)


class InprocWriter(Writer):
    def __init__(self, topic: InprocTopic) -> None:
        self._topic = topic

    def write(self, message: Any) -> None:
        self._topic.deliver(message)

    def close(self) -> None:
        return None
