"""Edges between hosts of one hetros graph: hetros's own bytes in DDS samples.

Inside one graph nothing needs ROS 2's conventions, and services carry hetros's
envelopes (request id, client), so an edge between hosts moves exactly the bytes the
shared-memory transport moves (the channel's codec), wrapped as one ``sequence<octet>``.
Each host publishes a channel on a topic of its own (``hetros/<project>/<host>/<channel>``),
so a reader subscribes only to the hosts the plan says feed it, and a subscriber that
gets a host's messages through shared memory never gets them twice.

Reliability is DDS's: reliable and keep_all, with ``depth`` unacknowledged samples at most
in the writer's history and ``depth`` samples at most in the reader's (Cyclone leaves a
sample it cannot store unacknowledged, so the writer resends it later, and the receive
thread goes on with other topics), so a network, host or subscriber that does not keep up
holds back the writer, which raises after ``publish_timeout``. Memory stays bounded on both
sides.
"""

from __future__ import annotations

import struct
import threading
import time
from collections import deque
from typing import Any

from cyclonedds._clayer import ddspy_read, ddspy_take
from cyclonedds.core import InstanceState, Policy, Qos, SampleState, ViewState
from cyclonedds.idl import make_idl_struct
from cyclonedds.idl import types as idl
from cyclonedds.internal import load_cyclonedds
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader

from ..._errors import SerializationError, TransportError
from ..._log import get_logger
from ..._qos import QoS
from .._base import Codec, Reader, Wake, Writer
from ._domain import DdsDomain, dds_qos, delete_entity
from ._endpoints import ANY_STATE, padded, write_sample

_sequence: Any = idl.sequence
_SAMPLE = make_idl_struct("HetrosSample", "hetros::dds_::Sample_", {"data": _sequence[idl.uint8]})
log = get_logger("hetros.dds")
_LENGTH = struct.Struct("<I")
# the binding has no writer call for it; Cyclone's C function does (a manual_by_topic writer)
_assert_liveliness = load_cyclonedds().dds_assert_liveliness
_HEAD = 8  # encapsulation, then the sequence's length
ACK_SLICE_NS = 20_000_000
UNREAD_STATE = SampleState.NotRead | ViewState.Any | InstanceState.Any


def edge_topic(project: str, host: str, channel: str) -> str:
    """The DDS topic on which ``host`` publishes ``channel`` of ``project``."""
    return f"hetros/{project}/{host}/{channel.lstrip('/')}"


def _edge_qos(qos: QoS, writer: bool) -> Qos:
    policies = list(dds_qos(qos))
    if qos.history == "keep_all":
        # at most ``depth`` samples in the writer's history and in the reader's: a reader that
        # does not take leaves the rest unacknowledged, and the writer waits (back-pressure)
        policies.append(Policy.ResourceLimits(max_samples=qos.depth, max_instances=1,
                                              max_samples_per_instance=qos.depth))
    return Qos(*policies)


class DdsEdgeWriter(Writer):
    """Publishes one channel of this host to the other hosts."""

    def __init__(self, domain: DdsDomain, topic: str, codec: Codec, qos: QoS) -> None:
        self.topic = topic
        self._codec = codec
        self._timeout = qos.publish_timeout
        self.reliable = qos.reliability == "reliable"
        self._lock = threading.Lock()
        self.writer = DataWriter(domain.participant, domain.topic(topic, _SAMPLE), qos=_edge_qos(qos, writer=True))
        self.sent = 0

    def write(self, message: Any) -> None:
        size = self._codec.size(message)
        data = padded(_HEAD + size)
        data[:4] = b"\x00\x01\x00\x00"
        _LENGTH.pack_into(data, 4, size)
        self._codec.encode_into(message, memoryview(data)[_HEAD:_HEAD + size])
        with self._lock:
            write_sample(self.writer, data, f"{self.topic} (to another host)", self._timeout)
            self.sent += 1

    def matched(self) -> int:
        return len(self.writer.get_matched_subscriptions())

    def assert_liveliness(self) -> None:
        _assert_liveliness(self.writer._ref)

    def linger(self, stop: threading.Event) -> bool:
        """Wait until every matched reader acknowledged what this reliable writer sent (at most
        ``publish_timeout``); whether they all did. The wait is cut in short slices: the binding
        holds the GIL inside ``dds_wait_for_acks``."""
        if not self.reliable:
            return True
        deadline = time.monotonic() + self._timeout
        while not stop.is_set():
            if self.writer.wait_for_acks(ACK_SLICE_NS):
                return True
            if time.monotonic() > deadline:
                return False
            time.sleep(0.005)
        return True

    def close(self) -> None:
        """Writers are shared per channel and deleted with the process' DDS participant."""


class DdsEdgeReader(Reader):
    """Takes one channel from the hosts that publish it to this subscriber.

    The participant's waiting thread moves arriving samples into a queue and wakes the node;
    the node's ``try_take`` decodes from the queue. Both sides are bounded: the queue holds
    at most ``depth`` samples, and on a reliable keep_all channel what does not fit stays
    in the DDS reader, whose history is ``depth`` samples too, so a subscriber that does not
    take holds back the remote writer (which raises after ``publish_timeout``) instead of
    growing this process; the node's takes pull the rest in. A keep_last channel keeps the
    newest ``depth``. A sample that is not hetros's framing or does not decode is dropped,
    counted (``dropped``) and logged; the reader goes on with the next one.
    """

    def __init__(self, domain: DdsDomain, topics: list[str], codec: Codec, qos: QoS, wake: Wake) -> None:
        self._codec = codec
        self._wake = wake
        self._depth = qos.depth
        self._blocks = qos.blocks_publisher
        self._queue: deque[tuple[str, bytes, int]] = deque(maxlen=None if self._blocks else qos.depth)
        self._lifespan_ns = None if qos.lifespan is None else int(qos.lifespan * 1e9)
        self.expired = 0
        self._lock = threading.Lock()
        self.received = 0
        self.dropped = 0
        self.readers = [DataReader(domain.participant, domain.topic(topic, _SAMPLE), qos=_edge_qos(qos, writer=False))
                        for topic in topics]
        for reader in self.readers:
            domain.watch(reader, self._arrived, unread_only=True)

    def _fill(self) -> bool:
        """Move samples from the DDS readers into the queue while it has room; whether any came."""
        arrived = False
        with self._lock:
            for reader in self.readers:
                while not self._blocks or len(self._queue) < self._depth:
                    taken = _take_one(reader)
                    if taken is None:
                        break
                    data, valid, sent_ns = taken
                    if valid:
                        self._queue.append((reader.topic.name, data, sent_ns))
                        arrived = True
        return arrived

    def _arrived(self) -> None:
        if self._fill():
            self._wake()
        if self._blocks:
            # what did not fit stays in the DDS reader: marked read, it wakes the waiting thread no
            # more (it spun a CPU while a subscriber did not take); the node's takes pull it in
            with self._lock:
                for reader in self.readers:
                    ddspy_read(reader._ref, UNREAD_STATE, 1 << 16)

    def try_take(self) -> Any | None:
        while True:
            if not self._blocks:
                self._fill()  # keep_last: the newest ``depth``, whatever the waiting thread moved yet
            try:
                topic, data, sent_ns = self._queue.popleft()
            except IndexError:
                if self._blocks and self._fill():
                    continue
                return None
            if self._blocks and len(self._queue) < self._depth // 2 + 1:
                self._fill()  # what waited in the DDS reader for room
            if self._lifespan_ns is not None and time.time_ns() - sent_ns > self._lifespan_ns:
                self.expired += 1  # Cyclone drops it from its history; here it may wait in the queue
                continue
            try:
                message = self._decode(topic, data)
            except SerializationError as exc:
                self.dropped += 1
                log.error("%s: dropped a malformed sample from another host (%d so far): %s", topic,
                          self.dropped, exc)
                continue
            self.received += 1
            return message

    def _decode(self, topic: str, data: bytes) -> Any:
        if len(data) < _HEAD or data[1] != 1:
            raise SerializationError(f"a sample of {topic} is not hetros's framing (starts {data[:_HEAD].hex(' ')})")
        (size,) = _LENGTH.unpack_from(data, 4)
        if _HEAD + size > len(data):
            raise SerializationError(f"a sample of {topic} says {size} bytes and holds {len(data) - _HEAD}")
        return self._codec.decode(memoryview(data)[_HEAD:_HEAD + size])

    def pending(self) -> bool:
        # an empty queue may only mean the waiting thread has not moved what arrived yet: look, and only
        # then ask the queue (a fill in that thread holds the lock until what it took is in the queue)
        return self._fill() or bool(self._queue)

    def matched(self) -> int:
        return sum(len(r.get_matched_publications()) for r in self.readers)

    def liveliness(self) -> tuple[int, int]:
        """Cyclone's own account, by the QoS's liveliness policy mapped one to one."""
        statuses = [reader.get_liveliness_changed_status() for reader in self.readers]  # type: ignore[no-untyped-call]
        return sum(s.alive_count for s in statuses), sum(s.not_alive_count for s in statuses)

    def close(self) -> None:
        with self._lock:
            readers, self.readers = self.readers, []
        for reader in readers:
            delete_entity(reader)


def _take_one(reader: DataReader[Any]) -> tuple[bytes, bool, int] | None:
    """(bytes, valid, source timestamp in ns of the wall clock) of the next sample, or None."""
    batch = ddspy_take(reader._ref, ANY_STATE, 1)
    if isinstance(batch, int):
        raise TransportError(f"taking from DDS reader {reader.topic.name} failed (return code {batch})")
    if not batch:
        return None
    data, info = batch[0]
    return data, bool(info.valid_data), int(info.source_timestamp)

