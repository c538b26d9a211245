"""The node API's readers and writers for a node that speaks only ROS 1 (``kind: ros1`` targets).

Topics: a writer publishes on the node's TCPROS publication; a reader reads its
connections in the node's own thread (``_stream``), so no thread stands between the
socket and a callback. Services use the same request/reply envelopes as every other mapping,
``(request_id, client, message)``, so ``Service`` and ``Client`` do not know they are
talking ROS 1: a ROSRPC request becomes an envelope in the server's FIFO and waits for
the reply envelope; a client's request envelope becomes one ROSRPC call on a worker
thread, whose answer (or error) comes back as a reply envelope.
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any

from ..._errors import Error, ShutdownError, TransportError
from ..._log import get_logger
from ..._qos import QoS
from .._base import Reader, Wake, Writer
from .._inproc import Mailbox
from ._header import MAX_FRAME
from ._peer import Ros1Peer, Ros1Publication
from ._stream import Ros1StreamReader, SocketWaiter
from ._types import Ros1ServiceType, Ros1Type

log = get_logger("hetros.ros1")

# the client name a ROSRPC caller gets in a request envelope (no hetros node has it: names have no ':')
ROSRPC_CLIENT = "rosrpc:"


class Ros1Writer(Writer):
    """Publishes a node's topic to its ROS 1 subscribers (latched when the topic is transient_local)."""

    def __init__(self, publication: Ros1Publication) -> None:
        self._publication = publication

    def write(self, message: Any) -> None:
        self._publication.publish(message)

    def close(self) -> None:
        self._publication.close()


def open_ros1_reader(peer: Ros1Peer, topic: str, kind: Ros1Type, qos: QoS, waiter: SocketWaiter,
                     wake: Wake) -> Reader:
    """Subscribe over TCPROS, read in the node's thread (see ``_stream``).

    A reliable topic reads one frame per take: a node that falls behind leaves the rest in
    the kernel and TCP holds the ROS 1 publisher; nothing is dropped on this side.
    keep_last keeps the newest ``depth``, as ROS 1's ``queue_size`` does.
    """
    reader = Ros1StreamReader(topic, kind, qos, waiter, wake, MAX_FRAME)
    subscription = peer.subscribe(topic, kind, attach=reader.add)
    return _Ros1Reader(reader, subscription.close)


class _Ros1Reader(Reader):
    def __init__(self, reader: Ros1StreamReader, release: Any) -> None:
        self._reader = reader
        self._release = release

    def try_take(self) -> Any | None:
        return self._reader.try_take()

    def taker(self) -> Callable[[], Any | None]:
        return self._reader.try_take

    def close(self) -> None:
        self._release()
        self._reader.close()


class Ros1ServiceServer:
    """A node's service, served to ROS 1 clients over ROSRPC through the node's executor.

    ``reader`` is what ``Service`` takes requests from; ``writer`` is where its replies go
    (every reply channel of this service, whatever client name the envelope carries).
    """

    def __init__(self, peer: Ros1Peer, service: str, kind: Ros1ServiceType, qos: QoS, wake: Wake,
                 stop: threading.Event) -> None:
        self.service = service
        self._stop = stop
        self._ids = itertools.count(1)
        self._pending: dict[int, Future[Any]] = {}
        self._lock = threading.Lock()
        self.reader = Mailbox(service, peer.name, qos, wake)
        self.writer = _ReplyWriter(self)
        peer.advertise_service(service, kind, self._handle)

    def _handle(self, request: Any) -> Any:
        """Runs on the ROSRPC connection's thread: queue the request, wait for the node's reply."""
        future: Future[Any] = Future()
        with self._lock:
            request_id = next(self._ids)
            self._pending[request_id] = future
        try:
            self.reader.put((request_id, f"{ROSRPC_CLIENT}{request_id}", request), float("inf"), self._stop)
            while True:
                try:
                    return future.result(timeout=0.2)
                except FutureTimeout:
                    if self._stop.is_set():
                        raise ShutdownError(f"service {self.service} is shutting down") from None
        finally:
            with self._lock:
                self._pending.pop(request_id, None)

    def _reply(self, envelope: tuple[int, str, Any]) -> None:
        with self._lock:
            future = self._pending.get(envelope[0])
        if future is not None and not future.done():
            future.set_result(envelope[2])


class _ReplyWriter(Writer):
    def __init__(self, server: Ros1ServiceServer) -> None:
        self._server = server

    def write(self, message: Any) -> None:
        self._server._reply(message)

    def close(self) -> None:
        return None


class Ros1ServiceCaller:
    """A node's client of a ROS 1 service: ``writer`` takes request envelopes, ``reader`` gives replies.

    Each request is one ROSRPC call on a worker thread (the node's thread never blocks on
    the network); a failed call comes back as the exception in the reply envelope.
    """

    def __init__(self, peer: Ros1Peer, service: str, kind: Ros1ServiceType, qos: QoS) -> None:
        self._peer = peer
        self._service = service
        self._kind = kind
        self._calls = ThreadPoolExecutor(max_workers=4, thread_name_prefix=f"hetros-ros1-call {service}")
        self._wake: Wake = lambda: None
        self.reader = Mailbox(service, peer.name, qos, self._woken)
        self.writer = _CallWriter(self)

    def _woken(self) -> None:
        self._wake()

    def attach(self, wake: Wake) -> Reader:
        self._wake = wake
        return self.reader

    def _call(self, envelope: tuple[int, str, Any]) -> None:
        request_id, client, request = envelope
        try:
            reply: Any = self._peer.call_service(self._service, self._kind, request)
        except Error as exc:
            reply = exc
        except Exception as exc:  # the caller gets it as the call's failure, never a silent loss
            reply = TransportError(f"calling ROS 1 service {self._service} failed: {type(exc).__name__}: {exc}")
        self.reader.put((request_id, client, reply), float("inf"), None)

    def close(self) -> None:
        self._calls.shutdown(wait=False, cancel_futures=True)
        self.reader.close()


class _CallWriter(Writer):
    def __init__(self, caller: Ros1ServiceCaller) -> None:
        self._caller = caller

    def write(self, message: Any) -> None:
        self._caller._calls.submit(self._caller._call, message)

    def close(self) -> None:
        self._caller.close()
