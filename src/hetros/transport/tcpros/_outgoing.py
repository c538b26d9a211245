"""Sending TCPROS frames to one subscriber without letting it stall the publisher."""

from __future__ import annotations

import select
import socket
import threading
import time
from collections import deque

from ..._errors import PublishTimeoutError
from ..._log import get_logger
from ..._qos import QoS
from ._types import Payload

log = get_logger("hetros.ros1")

# how long a publisher keeps writing a frame the subscriber is taking, before the rest is copied aside
_PATIENCE = 0.05


def send_parts(sock: socket.socket, parts: list[Payload]) -> None:
    """One vectored write of ``parts`` on a blocking socket, continued where the kernel stopped."""
    total = sum(len(part) for part in parts)
    sent = sock.sendmsg(parts)
    while sent < total:
        parts, total = _rest(parts, sent), total - sent
        sent = sock.sendmsg(parts)


def _rest(parts: list[Payload], sent: int) -> list[Payload]:
    """What is left of ``parts`` after the first ``sent`` bytes."""
    rest: list[Payload] = []
    for part in parts:
        if sent >= len(part):
            sent -= len(part)
            continue
        rest.append(memoryview(part)[sent:])
        sent = 0
    return rest


class SubscriberLink:
    """One ROS 1 subscriber's connection, fed by its publication.

    A frame goes straight to the socket (non-blocking, from the message's own memory):
    the common case costs one system call and no thread, and a large frame that the
    subscriber is reading goes on being written for up to ``_PATIENCE``. What the
    subscriber does not take by then waits, copied, in a backlog that a helper thread
    drains as the socket allows, so a subscriber that stops reading (a stuck process, a
    node busy for seconds) never freezes the publisher. The backlog holds ``depth``
    frames besides the one under way: keep_last drops the oldest waiting one, as rospy's
    ``queue_size`` does; reliable keep_all makes the publisher wait, and after
    ``publish_timeout`` raises PublishTimeoutError naming the subscriber.
    """

    def __init__(self, sock: socket.socket, who: str, topic: str, qos: QoS) -> None:
        sock.setblocking(False)
        self.sock = sock
        self.who = who
        self.topic = topic
        self.qos = qos
        self.dropped = 0
        self._cond = threading.Condition()
        self._backlog: deque[memoryview] = deque()
        self._head_sent = 0
        self._drainer: threading.Thread | None = None
        self._failure: OSError | None = None
        self._closed = False
        self._writable = select.poll()
        self._writable.register(sock, select.POLLOUT)

    def send(self, frame: list[Payload], total: int) -> None:
        """Raises OSError when the subscriber is gone, PublishTimeoutError as described above."""
        with self._cond:
            if self._failure is not None:
                raise self._failure
            if not self._backlog:
                sent = self._try_send(frame)
                if sent < total:
                    give_up = time.monotonic() + _PATIENCE
                    while sent < total and time.monotonic() < give_up:
                        if self._writable.poll(max(1, int((give_up - time.monotonic()) * 1000))):
                            sent += self._try_send(_rest(frame, sent))
                if sent < total:
                    self._queue(_rest(frame, sent))
                return
            if len(self._backlog) > self.qos.depth:
                self._make_room()
            self._queue(frame)

    def _try_send(self, parts: list[Payload]) -> int:
        try:
            return self.sock.sendmsg(parts)
        except (BlockingIOError, InterruptedError):
            return 0

    def _queue(self, parts: list[Payload]) -> None:
        self._backlog.append(memoryview(b"".join(parts)))  # a copy: the caller may reuse its memory
        if self._drainer is None:
            self._drainer = threading.Thread(target=self._drain, name=f"hetros-ros1-out {self.topic}", daemon=True)
            self._drainer.start()
        self._cond.notify_all()

    def _make_room(self) -> None:
        if not self.qos.blocks_publisher:
            del self._backlog[1]  # the oldest waiting frame; the head may be under way
            self.dropped += 1
            if self.dropped in (1, 10, 100) or self.dropped % 1000 == 0:
                log.warning("%s: ROS 1 subscriber %s does not keep up; %d message(s) dropped for it so far "
                            "(keep_last, depth %d)", self.topic, self.who, self.dropped, self.qos.depth)
            return
        deadline = time.monotonic() + self.qos.publish_timeout
        while len(self._backlog) > self.qos.depth and self._failure is None and not self._closed:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise PublishTimeoutError(
                    f"publishing on {self.topic}: ROS 1 subscriber {self.who} has not read for "
                    f"{self.qos.publish_timeout:g} s and {len(self._backlog)} messages wait for it "
                    "(reliable + keep_all blocks the publisher); make it faster, raise 'depth' or "
                    "'publish_timeout', or use keep_last"
                )
            self._cond.wait(min(remaining, 0.1))
        if self._failure is not None:
            raise self._failure

    def _drain(self) -> None:
        writable = select.poll()
        writable.register(self.sock, select.POLLOUT)
        while True:
            with self._cond:
                while not self._backlog and not self._closed:
                    self._cond.wait()
                if self._closed:
                    return
            writable.poll(100)
            with self._cond:
                if self._closed:
                    return
                head = self._backlog[0]
                try:
                    self._head_sent += self.sock.send(head[self._head_sent:])
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError as exc:
                    self._failure = exc
                    self._cond.notify_all()
                    return
                if self._head_sent == len(head):
                    self._backlog.popleft()
                    self._head_sent = 0
                    self._cond.notify_all()

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        self.sock.close()
