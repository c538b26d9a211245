"""Topic and service endpoints on DDS with ROS 2's names, QoS and bytes.

Samples go through the binding as opaque bytes: hetros's generated codecs make the
XCDR1 body (byte for byte what ROS 2 makes) and ``ddspy_write``/``ddspy_take``
move it, so no per-field Python serializer runs (the binding's own path takes
~150 ms for a 3 MiB ``sequence<uint8>``). Services carry rmw_cyclonedds's request
header (client id, sequence number) in front of the body, in the same CDR stream.
Arriving samples are handled on the participant's waiting thread (``_waiter``), which
only decodes and hands over; hetros's own transports do the rest.
"""

from __future__ import annotations

import itertools
import struct
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from typing import Any

from cyclonedds._clayer import ddspy_take, ddspy_write
from cyclonedds.core import InstanceState, SampleState, ViewState
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader

from ..._errors import Error, PublishTimeoutError, SerializationError, TransportError
from ..._log import get_logger
from ..._qos import QoS
from ...msg import TypeRegistry
from .._codec import CDR_LE, MessageCodec
from ._domain import SERVICE_QOS, DdsDomain, dds_qos
from ._idl import idl_type
from ._names import reply_topic, request_topic, topic_name

log = get_logger("hetros.dds")

_HEADER = struct.Struct("<Qq")  # rmw_cyclonedds: client id, sequence number
ANY_STATE = SampleState.Any | ViewState.Any | InstanceState.Any
_TAKE_AT_ONCE = 64
# DDS_RETCODE_TIMEOUT: a reliable writer's history stayed full for max_blocking_time
_RETCODE_TIMEOUT = -10


def type_hash_user_data(types: TypeRegistry, typename: str) -> bytes:
    """What rmw_cyclonedds puts in an endpoint's USER_DATA so ROS 2 tools learn its type hash."""
    return f"typehash={types.store.hash_rihs01(typename)};".encode()


def _handle(instance_handle: int) -> int:
    """Instance handles as the unsigned 64-bit numbers they are (the binding gives some signed)."""
    return int(instance_handle) & 0xFFFF_FFFF_FFFF_FFFF


def padded(size: int) -> bytearray:
    return bytearray((size + 3) & ~3)  # DDS payloads are whole 4-byte words


def write_sample(writer: DataWriter[Any], data: bytes | bytearray, what: str, timeout: float) -> None:
    """Write one sample, waiting up to ``timeout`` while a reliable reader's history is full.

    The binding holds the GIL inside ``dds_write``, so a write that blocked there would stop every
    Python thread of the process, Cyclone's listener callbacks included (and with them the
    acknowledgements that would unblock it, and the leases of the process' participants). So
    writers never block in DDS (``max_blocking_time`` 0, see ``dds_qos``); the wait is here, in
    short sleeps that let everything else run.
    """
    deadline = None
    pause = 0.0002
    while True:
        code = ddspy_write(writer._ref, data)
        if code != _RETCODE_TIMEOUT:
            break
        now = time.monotonic()
        deadline = deadline or now + timeout
        if now >= deadline:
            raise PublishTimeoutError(f"{what}: a DDS reader did not take the sample within {timeout:g} s "
                                      "(reliable back-pressure); the sample was not sent")
        time.sleep(pause)
        pause = min(pause * 2, 0.005)
    if code < 0:
        raise TransportError(f"{what}: DDS refused the sample (return code {code})")


def _taken(reader: DataReader[Any], ignore: set[int] | frozenset[int] = frozenset()) -> list[bytes]:
    """Every valid sample waiting, except those of the writers in ``ignore``."""
    samples: list[bytes] = []
    while True:
        batch = ddspy_take(reader._ref, ANY_STATE, _TAKE_AT_ONCE)
        if isinstance(batch, int):
            raise TransportError(f"taking from DDS reader failed (return code {batch})")
        samples += [data for data, info in batch
                    if info.valid_data and _handle(info.publication_handle) not in ignore]
        if len(batch) < _TAKE_AT_ONCE:
            return samples


class DdsTopicWriter:
    """Publishes one topic under its ROS 2 name."""

    def __init__(self, domain: DdsDomain, types: TypeRegistry, topic: str, typename: str, qos: QoS,
                 dds_topic: str | None = None) -> None:
        self.topic = topic
        self._codec = MessageCodec(types, typename)
        self._timeout = qos.publish_timeout
        name = topic_name(topic) if dds_topic is None else dds_topic
        self.writer = DataWriter(domain.participant, domain.topic(name, idl_type(types, typename)),
                                 qos=dds_qos(qos, type_hash_user_data(types, typename)))
        domain.local_writers.add(_handle(self.writer.instance_handle))

    @classmethod
    def raw(cls, domain: DdsDomain, types: TypeRegistry, dds_topic: str, typename: str, qos: QoS) -> DdsTopicWriter:
        """A writer on a DDS topic outside ROS 2's ``rt/`` names (``ros_discovery_info``)."""
        return cls(domain, types, dds_topic, typename, qos, dds_topic=dds_topic)

    def write(self, message: Any) -> None:
        data = padded(self._codec.size(message))
        self._codec.encode_into(message, memoryview(data))
        write_sample(self.writer, data, f"DDS topic {self.topic}", self._timeout)

    def matched(self) -> int:
        return len(self.writer.get_matched_subscriptions())


class DdsTopicReader:
    """Subscribes one topic under its ROS 2 name; ``deliver`` gets read-only messages."""

    def __init__(self, domain: DdsDomain, types: TypeRegistry, topic: str, typename: str, qos: QoS,
                 deliver: Callable[[Any], None]) -> None:
        self.topic = topic
        self._codec = MessageCodec(types, typename)
        self._deliver = deliver
        self._own = domain.local_writers
        self.received = 0
        self.reader = DataReader(domain.participant, domain.topic(topic_name(topic), idl_type(types, typename)),
                                 qos=dds_qos(qos, type_hash_user_data(types, typename)))
        domain.watch(self.reader, self._available)

    def _available(self) -> None:
        for data in _taken(self.reader, self._own):  # a topic both exported and imported: not our own samples back
            try:
                message = self._codec.decode(memoryview(data))
            except SerializationError as exc:
                log.error("DDS topic %s: dropped a sample that does not decode (%s)", self.topic, exc)
                continue
            self.received += 1
            try:
                self._deliver(message)
            except Error as exc:
                log.error("DDS topic %s: could not hand a sample on: %s", self.topic, exc)

    def matched(self) -> int:
        return len(self.reader.get_matched_publications())


class _RequestCodec:
    """A service request or reply: encapsulation, rmw_cyclonedds's header, then the body."""

    def __init__(self, types: TypeRegistry, typename: str, service: str) -> None:
        self._cdr = types.codec(typename)
        self._what = f"service {service} ({typename})"

    def encode(self, client_id: int, sequence: int, message: Any) -> bytearray:
        data = padded(4 + _HEADER.size + self._cdr.size(message))
        view = memoryview(data)
        view[:4] = CDR_LE
        _HEADER.pack_into(view, 4, client_id, sequence)
        self._cdr.encode(message, view[4:], _HEADER.size)
        return data

    def decode(self, data: bytes) -> tuple[int, int, Any]:
        if len(data) < 4 + _HEADER.size or data[1] != 1:
            raise SerializationError(f"{self._what}: {len(data)} bytes are not little-endian XCDR1 with "
                                     f"rmw_cyclonedds's 16-byte request header (start {data[:4].hex(' ')})")
        client_id, sequence = _HEADER.unpack_from(data, 4)
        return client_id, sequence, self._cdr.decode(memoryview(data)[4:], _HEADER.size)

    def decode_all(self, reader: DataReader[Any], what: str) -> Iterator[tuple[int, int, Any]]:
        """Every waiting sample of ``reader`` decoded; one that does not decode is dropped and logged."""
        for data in _taken(reader):
            try:
                yield self.decode(data)
            except SerializationError as exc:
                log.error("%s: dropped a %s (%s)", self._what, what, exc)


class DdsServiceServer:
    """Serves one service to ROS 2 clients. ``handle(request, respond)`` may answer later, from
    any thread, by calling ``respond(response)`` once."""

    def __init__(self, domain: DdsDomain, types: TypeRegistry, service: str, srv_typename: str,
                 handle: Callable[[Any, Callable[[Any], None]], None]) -> None:
        self.service = service
        self._handle = handle
        self._requests = _RequestCodec(types, f"{srv_typename}_Request", service)
        self._replies = _RequestCodec(types, f"{srv_typename}_Response", service)
        self._lock = threading.Lock()
        self.writer = DataWriter(
            domain.participant, domain.topic(reply_topic(service), idl_type(types, f"{srv_typename}_Response", True)),
            qos=dds_qos(SERVICE_QOS, type_hash_user_data(types, f"{srv_typename}_Response")))
        self.reader = DataReader(
            domain.participant, domain.topic(request_topic(service), idl_type(types, f"{srv_typename}_Request", True)),
            qos=dds_qos(SERVICE_QOS, type_hash_user_data(types, f"{srv_typename}_Request")))
        domain.watch(self.reader, self._available)

    def _available(self) -> None:
        for client_id, sequence, request in self._requests.decode_all(self.reader, "request"):
            try:
                self._handle(request, self._responder(client_id, sequence))
            except Error as exc:
                log.error("%s: the request of client %016x #%d failed: %s", self.service, client_id, sequence, exc)

    def _responder(self, client_id: int, sequence: int) -> Callable[[Any], None]:
        answered = threading.Event()

        def respond(response: Any) -> None:
            if answered.is_set():
                raise TransportError(f"{self.service}: request #{sequence} was answered already")
            answered.set()
            with self._lock:
                write_sample(self.writer, self._replies.encode(client_id, sequence, response),
                       f"reply of {self.service}", SERVICE_QOS.publish_timeout)

        return respond


class DdsServiceClient:
    """Calls one ROS 2 service; replies are matched by (client id, sequence number)."""

    def __init__(self, domain: DdsDomain, types: TypeRegistry, service: str, srv_typename: str) -> None:
        self.service = service
        self._requests = _RequestCodec(types, f"{srv_typename}_Request", service)
        self._replies = _RequestCodec(types, f"{srv_typename}_Response", service)
        self._sequence = itertools.count(1)
        self._pending: dict[int, Future[Any]] = {}
        self._lock = threading.Lock()
        self.writer = DataWriter(
            domain.participant, domain.topic(request_topic(service), idl_type(types, f"{srv_typename}_Request", True)),
            qos=dds_qos(SERVICE_QOS, type_hash_user_data(types, f"{srv_typename}_Request")))
        # as rmw_cyclonedds: the request writer's instance handle identifies the client
        self.client_id = _handle(self.writer.instance_handle)
        self.reader = DataReader(
            domain.participant, domain.topic(reply_topic(service), idl_type(types, f"{srv_typename}_Response", True)),
            qos=dds_qos(SERVICE_QOS, type_hash_user_data(types, f"{srv_typename}_Response")))
        domain.watch(self.reader, self._available)

    def ready(self) -> bool:
        """A server's request reader and reply writer are both matched (ROS 2's service_is_ready)."""
        return bool(self.writer.get_matched_subscriptions()) and bool(self.reader.get_matched_publications())

    def call_async(self, request: Any) -> Future[Any]:
        future: Future[Any] = Future()
        with self._lock:
            sequence = next(self._sequence)
            self._pending[sequence] = future
        try:
            write_sample(self.writer, self._requests.encode(self.client_id, sequence, request),
                   f"request to {self.service}", SERVICE_QOS.publish_timeout)
        except Error:
            with self._lock:
                self._pending.pop(sequence, None)
            raise
        return future

    def forget(self, future: Future[Any]) -> None:
        """Stop waiting for a call's reply (it timed out)."""
        with self._lock:
            self._pending = {k: v for k, v in self._pending.items() if v is not future}

    def _available(self) -> None:
        for client_id, sequence, response in self._replies.decode_all(self.reader, "reply"):
            if client_id != self.client_id:
                continue  # another client's reply: every client of a service reads every reply
            with self._lock:
                future = self._pending.pop(sequence, None)
            if future is not None and not future.done():
                future.set_result(response)
