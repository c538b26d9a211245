"""Reading TCPROS in the node's own thread: no reader thread between the socket and a callback.

A ``kind: ros1`` node's executor blocks on one epoll set (:class:`SocketWaiter`) that holds
every TCPROS connection its subscriptions have, plus an eventfd that in-process wake-ups
(service requests, shutdown, a second waiting thread) write to. A readable connection
wakes its subscription; the subscription then reads the frame itself, without blocking:
a frame that arrives in pieces (a slow or malicious peer) is assembled across calls and
never holds the node. A reliable subscription reads one frame per take, so a node that
falls behind leaves the rest in the kernel and TCP pushes back on the publisher; a
keep_last one keeps the newest ``depth`` frames of what each read brings (up to 64 KiB of
small frames at once), as ROS 1's ``queue_size`` does.
"""

from __future__ import annotations

import os
import select
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from ..._errors import ProtocolError, SerializationError
from ..._log import get_logger
from ..._qos import QoS
from .._base import Reader, Wake
from ._header import FRAME, frame_length
from ._types import Ros1Kind

log = get_logger("hetros.ros1")

# frames up to this size are assembled in the connection's buffer; larger ones in memory of their own
_CHUNK = 1 << 16
_ONESHOT = select.EPOLLIN | select.EPOLLONESHOT
# how long a read waits for the next piece of a large frame under way, and for all of them
_PATIENCE_MS = 2
_PATIENCE_TOTAL = 0.01


class SocketWaiter:
    """One node's wait: an epoll set of TCPROS connections and an eventfd for in-process wake-ups.

    Each connection is armed once (EPOLLONESHOT): it fires one wake-up, and its reader
    re-arms it when it has read everything there was. A node that does not take from a
    subscription for a while therefore costs no CPU, however much waits in the socket.
    Implements the executor's ``WaitSource``.
    """

    def __init__(self) -> None:
        self._epoll = select.epoll()
        self._interrupt = os.eventfd(0, os.EFD_NONBLOCK | os.EFD_CLOEXEC)
        self._epoll.register(self._interrupt, select.EPOLLIN)
        self._ready: dict[int, Callable[[], None]] = {}
        self._lock = threading.Lock()
        self._closed = False

    def watch(self, fd: int, ready: Callable[[], None]) -> None:
        with self._lock:
            self._ready[fd] = ready
            self._epoll.register(fd, _ONESHOT)

    def rearm(self, fd: int) -> None:
        try:
            self._epoll.modify(fd, _ONESHOT)
        except (OSError, ValueError):
            pass  # the connection was closed meanwhile: its reader notices on its next read

    def forget(self, fd: int) -> None:
        with self._lock:
            self._ready.pop(fd, None)
            try:
                self._epoll.unregister(fd)
            except (OSError, ValueError):
                pass

    def wait(self, timeout: float | None) -> None:
        self._dispatch(-1 if timeout is None else max(timeout, 0.0))

    def poll(self) -> None:
        self._dispatch(0)

    def interrupt(self) -> None:
        if not self._closed:
            os.eventfd_write(self._interrupt, 1)

    def _dispatch(self, timeout: float) -> None:
        try:
            events = self._epoll.poll(timeout)
        except ValueError:
            return  # closed: the executor is stopping
        for fd, _mask in events:
            if fd == self._interrupt:
                try:
                    os.eventfd_read(self._interrupt)
                except BlockingIOError:
                    pass
                continue
            ready = self._ready.get(fd)
            if ready is not None:
                ready()

    def close(self) -> None:
        """After the executor stopped: a late wait or interrupt does nothing."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self._epoll.close()
        os.close(self._interrupt)


class FrameStream:
    """One TCPROS connection read without blocking: ``next_frame`` gives complete frames only.

    A frame up to ``_CHUNK`` bytes is copied out of the connection's buffer (the message
    keeps it); a larger one lands in memory of its own that the kernel maps as bytes
    arrive, so a length prefix that lies costs the peer what it sent, not what it announced.
    The rest of a large frame is usually in flight: a read waits up to ``_PATIENCE_MS`` for
    each next piece (going back to the executor between pieces would cost a wake-up each)
    and ``_PATIENCE_TOTAL`` in all, so a peer that trickles or stalls mid-frame does not
    hold the node.
    """

    def __init__(self, sock: socket.socket, peer: str, max_frame: int) -> None:
        sock.setblocking(False)
        self.sock = sock
        self.peer = peer
        self._max_frame = max_frame
        self._buffer = memoryview(bytearray(_CHUNK))
        self._start = 0
        self._end = 0
        self._large: memoryview | None = None
        self._large_got = 0
        self._readable = select.poll()
        self._readable.register(sock, select.POLLIN)

    def next_frame(self, receive: bool = True) -> bytes | memoryview | None:
        """The next complete frame, None when the socket has no more for now (or, without
        ``receive``, when no complete small frame is already buffered: no system call then).

        Raises ConnectionError when the peer closed, ProtocolError on a refused length.
        """
        if self._large is not None:
            return self._fill_large() if receive else None
        while True:
            available = self._end - self._start
            if available >= FRAME.size:
                length = frame_length(FRAME.unpack_from(self._buffer, self._start)[0], self.peer, self._max_frame)
                body = self._start + FRAME.size
                if self._end - body >= length:
                    self._start = body + length
                    return bytes(self._buffer[body:body + length])
                if not receive:
                    return None
                if length > _CHUNK - FRAME.size:
                    large = memoryview(np.empty(length, np.uint8).data)
                    have = self._end - body
                    large[:have] = self._buffer[body:self._end]
                    self._large, self._large_got = large, have
                    self._start = self._end = 0
                    return self._fill_large()
            if self._start:
                self._buffer[:available] = self._buffer[self._start:self._end]
                self._start, self._end = 0, available
            if not receive or not self._receive_into(self._buffer, self._end):
                return None

    def _fill_large(self) -> memoryview | None:
        large = self._large
        assert large is not None
        give_up = time.monotonic() + _PATIENCE_TOTAL
        while self._large_got < len(large):
            if not self._receive_into(large, self._large_got) and not (
                    time.monotonic() < give_up and self._readable.poll(_PATIENCE_MS)
                    and self._receive_into(large, self._large_got)):
                return None
        self._large = None
        return large

    def _receive_into(self, buffer: memoryview, at: int) -> bool:
        """Read what the socket has into ``buffer[at:]``; False when it has nothing now."""
        try:
            count = self.sock.recv_into(buffer[at:])
        except (BlockingIOError, InterruptedError):
            return False
        if not count:
            raise ConnectionError(f"{self.peer} closed the connection")
        if buffer is self._buffer:
            self._end += count
        else:
            self._large_got += count
        return True


class Ros1StreamReader(Reader):
    """A node's subscription to one ROS 1 topic, read in the node's thread from every publisher.

    ``wake`` runs (in the thread waiting on the node's :class:`SocketWaiter`) when a
    connection has data; ``try_take`` then reads it. Connections come from the
    subscription's connecting threads through :meth:`add`.
    """

    def __init__(self, topic: str, kind: Ros1Kind, qos: QoS, waiter: SocketWaiter, wake: Wake,
                 max_frame: int) -> None:
        self.topic = topic
        self._kind = kind
        self._waiter = waiter
        self._wake = wake
        self._max_frame = max_frame
        self._keep_last = not qos.blocks_publisher
        self._frames: deque[tuple[bytes | memoryview, FrameStream, Callable[[], None]]] = deque(
            maxlen=qos.depth if self._keep_last else None)
        self._streams: list[tuple[FrameStream, Callable[[], None]]] = []
        self._lock = threading.Lock()
        self._take_lock = threading.Lock()
        self._next = 0
        self._closed = False
        self.dropped = 0

    def add(self, sock: socket.socket, peer: str, gone: Callable[[], None]) -> None:
        """Read ``sock`` from now on (its handshake is done); ``gone`` runs when it closes."""
        stream = FrameStream(sock, peer, self._max_frame)
        with self._lock:
            if self._closed:
                sock.close()
                return
            self._streams.append((stream, gone))
        self._waiter.watch(sock.fileno(), self._wake)

    def try_take(self) -> Any | None:
        with self._take_lock:
            if not self._frames:
                self._read()
                if not self._frames:
                    return None
            frame, stream, gone = self._frames.popleft()
            try:
                return self._kind.deserialize(frame)
            except SerializationError as exc:
                log.error("%s: %s from %s; disconnected", self.topic, exc, stream.peer)
                self._drop(stream, gone)
                return None

    def _read(self) -> None:
        """The next frame, round robin over publishers; keep_last adds the newer ones already read.

        One system call brings the frame (and whatever followed it) on the way to a callback;
        finding the socket drained and re-arming it wait for the next take, after the callback.
        """
        with self._lock:
            streams = list(self._streams)
        for offset in range(len(streams)):
            stream, gone = streams[(self._next + offset) % len(streams)]
            try:
                frame = stream.next_frame()
                if frame is None:
                    self._waiter.rearm(stream.sock.fileno())
                    continue
                self._keep(frame, stream, gone)
                if self._keep_last:
                    while (frame := stream.next_frame(receive=False)) is not None:
                        self._keep(frame, stream, gone)
                self._next = (self._next + offset + 1) % len(streams)
                return
            except ProtocolError as exc:
                log.error("%s; disconnected", exc)
                self._drop(stream, gone)
            except OSError:
                self._drop(stream, gone)  # the publisher went away, or the subscription dropped it

    def _keep(self, frame: bytes | memoryview, stream: FrameStream, gone: Callable[[], None]) -> None:
        if self._keep_last and len(self._frames) == self._frames.maxlen:
            self.dropped += 1
        self._frames.append((frame, stream, gone))

    def _drop(self, stream: FrameStream, gone: Callable[[], None]) -> None:
        with self._lock:
            known = any(s is stream for s, _g in self._streams)
            self._streams = [(s, g) for s, g in self._streams if s is not stream]
        if known:
            self._release(stream)
            gone()

    def _release(self, stream: FrameStream) -> None:
        if stream.sock.fileno() != -1:
            self._waiter.forget(stream.sock.fileno())
        stream.sock.close()

    def close(self) -> None:
        with self._lock:
            self._closed = True
            streams, self._streams = self._streams, []
        for stream, _gone in streams:
            self._release(stream)
