"""Same-host, cross-process transport on iceoryx2 shared memory.

Layout, fixed by the static plan (no discovery at run time):

* one iceoryx2 publish-subscribe service per (topic, publishing target), so a
  process never receives through shared memory what it already delivered to
  itself in-process; all publishers of a service live in one process;
* one *wake channel* (an iceoryx2 event service) per subscribing node: every
  reader of the node has an event id on it, and the node's executor is the only
  thing that waits on it (no thread per reader);
* one *back channel* per publishing process, watched by one thread, that wakes
  publishers blocked on a full FIFO and connects late joiners to history;
* a small *credits* file in /dev/shm per service: the sequence number last
  published and, per subscriber slot, the sequence it last took, its pid and
  the wake channel and event id to notify. A reliable keep_all publisher
  computes each subscriber's fill level from it and blocks while a FIFO holds
  ``depth`` messages: back-pressure across processes, with a timeout and with
  crashed subscribers detected by pid.

Nothing on a reliable topic is lost without an error: a reader checks that the
sequence numbers of each service arrive without gaps and that what the credits
say was published does arrive (iceoryx2 skips a publisher it cannot connect to,
for example when the process is out of file descriptors, without telling the
receiver; that is the silent loss this check turns into a
:class:`~hetros.TransportError`).

Resources per endpoint: one iceoryx2 service (2 file descriptors) and one port
(1 for a subscriber, 4 for a publisher, 3 more per connection); per node one
wake channel (5); per process one back channel and one thread.

Every sample starts with a 16-byte header (sequence number, publisher slot,
reserved); the message follows in the codec's format (CDR for messages).
"""

from __future__ import annotations

import ctypes
import hashlib
import itertools
import logging
import mmap
import os
import resource
import struct
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import PublishTimeoutError, SerializationError, ShutdownError, TransportError
from ..msg import Message, freeze, get_path, set_path
from ._base import Codec, Reader, Wake, Writer
from ._codec import MessageCodec
from ._qos import QoS

os.environ.setdefault("IOX2_LOG_LEVEL", "Error")
import iceoryx2 as iox2

iox2.set_log_level(iox2.LogLevel.Error)

log = logging.getLogger("hetros.transport.shm")

SHM_DIR = Path("/dev/shm")
# Every sample: sequence number, publisher slot, layout, padding; then the message. With the
# CDR layout the 4-byte encapsulation sits at 28..32 so the CDR body starts 8-byte aligned.
HEADER = struct.Struct("<QII12x")
LAYOUT_CDR = 0
LAYOUT_SPLIT = 1
# The split layout (loaned messages): small part as CDR, primitive arrays as separate blobs
# at 64-byte aligned offsets, each named by its index in the type's array list.
SPLIT = struct.Struct("<II")
BLOB = struct.Struct("<IIQQ")
LOAN_RESERVE = 4096
# Plain messages up to this size are one contiguous CDR (one encode, arrays inline and read
# in place as views); larger ones use the split layout, whose blobs need no zeroing.
INLINE_LIMIT = 64 * 1024
MAX_SUBSCRIBER_SLOTS = 32
MAX_PUBLISHERS_PER_SERVICE = 8
MAX_EVENT_PORTS = 256
# iceoryx2's event latency grows with the id range (measured: 13 µs at 100, 25 µs at 4095,
# 215 µs at 65535), so ids are few; readers beyond that share an id (a spurious wake-up
# costs one empty receive).
MAX_EVENT_ID = 255
INTERRUPT_EVENT = 0
BORROW_LIMIT = 16
# A reader that sees published samples it cannot receive waits this long for a late connection
# before it reports them lost.
LOSS_GRACE = 0.5


INITIAL_SLOT = 4096


def reserved_bytes(qos: QoS, message_size: int | None) -> int:
    """Shared memory one service of a topic reserves (iceoryx2 sizes it up front, sparse).

    ``message_size`` is the CDR size of a fixed-size type, None when it varies: such slots
    start at 4 KiB and grow by powers of two as larger messages come.
    """
    buffer = qos.depth + 2 if qos.blocks_publisher else qos.depth
    history = qos.depth if qos.keeps_history else 0
    samples = MAX_SUBSCRIBER_SLOTS * (buffer + BORROW_LIMIT) + history + 2
    slot = HEADER.size + (message_size + 4 if message_size is not None else INITIAL_SLOT)
    return samples * slot


def segment_prefix(session: str) -> str:
    return f"hetros-{session}-"


def _align(value: int, to: int) -> int:
    return (value + to - 1) & -to


def _slot_memory(address: int, size: int, keepalive: object) -> memoryview:
    """Bytes at ``address`` as a memoryview that keeps ``keepalive`` alive while referenced."""
    raw = (ctypes.c_uint8 * size).from_address(address)
    raw._hetros_keepalive = keepalive  # type: ignore[attr-defined]
    return memoryview(raw).cast("B")


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


_SLOT_WORDS = 4
_WORD = struct.Struct("<Q")
_SLOT_TABLE = struct.Struct(f"<{_SLOT_WORDS * MAX_SUBSCRIBER_SLOTS}Q")


class Credits:
    """The credits file of one service.

    Layout (little endian u64): ``published`` sequence number, ``waiting`` (a publisher is
    blocked on a full FIFO, so takers must signal), ``version`` (bumped by every subscriber
    that joins or leaves, so the publisher rereads the slots only then), ``back_event`` (the
    publisher's event id on its process' back channel); then per subscriber slot: taken, pid,
    wake channel key, event id. Each word has one writer: the publishing process writes the
    head (but ``version``), a subscriber writes its own slot and bumps ``version``.
    """

    HEAD = 4
    SIZE = 8 * (HEAD + _SLOT_WORDS * MAX_SUBSCRIBER_SLOTS)

    def __init__(self, path: Path) -> None:
        self.path = path
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
        try:
            if os.fstat(fd).st_size < self.SIZE:
                os.ftruncate(fd, self.SIZE)
            self._map = mmap.mmap(fd, self.SIZE)
        finally:
            os.close(fd)
        self.words = np.frombuffer(self._map, dtype="<u8")
        self.slots = self.words[self.HEAD:].reshape(MAX_SUBSCRIBER_SLOTS, _SLOT_WORDS)

    # the hot words go through struct on the mapping: a numpy element access costs ~3x more
    @property
    def published(self) -> int:
        value: int = _WORD.unpack_from(self._map, 0)[0]
        return value

    @published.setter
    def published(self, seq: int) -> None:
        _WORD.pack_into(self._map, 0, seq)

    @property
    def waiting(self) -> bool:
        return bool(_WORD.unpack_from(self._map, 8)[0])

    @waiting.setter
    def waiting(self, flag: bool) -> None:
        _WORD.pack_into(self._map, 8, int(flag))

    @property
    def version(self) -> int:
        value: int = _WORD.unpack_from(self._map, 16)[0]
        return value

    @property
    def back_event(self) -> int:
        return int(self.words[3])

    @back_event.setter
    def back_event(self, event: int) -> None:
        self.words[3] = event

    def slot(self, index: int) -> tuple[int, int]:
        taken, pid, _key, _event = self.slots[index]
        return int(taken), int(pid)

    def join(self, index: int, taken: int, wake_key: int, event: int) -> None:
        self.slots[index] = (taken, os.getpid(), wake_key, event)
        self.words[2] += 1

    def leave(self, index: int) -> None:
        self.slots[index] = (0, 0, 0, 0)
        self.words[2] += 1

    def set_taken(self, index: int, taken: int) -> None:
        _WORD.pack_into(self._map, 8 * (self.HEAD + _SLOT_WORDS * index), taken)

    def subscribers(self) -> list[tuple[int, int]]:
        """(wake channel key, event id) of every live subscriber slot."""
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        return [(words[i + 2], words[i + 3]) for i in range(0, len(words), _SLOT_WORDS) if words[i + 1]]

    def max_fill(self, published: int) -> int:
        """The fullest live subscriber FIFO, in messages (0 without subscribers)."""
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        return max((published - words[i] for i in range(0, len(words), _SLOT_WORDS) if words[i + 1]),
                   default=0)

    def full_slots(self, published: int, depth: int) -> list[int]:
        """Slots of live subscribers whose FIFO holds ``depth`` messages already."""
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        return [i // _SLOT_WORDS for i in range(0, len(words), _SLOT_WORDS)
                if words[i + 1] and words[i] + depth <= published]

    def close(self) -> None:
        del self.words, self.slots
        try:
            self._map.close()
        except BufferError:
            pass


def _channel_key(session: str, owner: str) -> int:
    """A wake channel's key: 63 bits, never 0 (0 marks an empty slot)."""
    digest = hashlib.sha1(f"{session}/{owner}".encode()).digest()
    return (int.from_bytes(digest[:8], "little") >> 1) or 1


def _event_service(node: Any, name: str, what: str) -> Any:
    try:
        return (node.service_builder(iox2.ServiceName.new(name)).event()
                .max_listeners(MAX_EVENT_PORTS).max_notifiers(MAX_EVENT_PORTS)
                .event_id_max_value(MAX_EVENT_ID).open_or_create())
    except Exception as exc:  # iceoryx2 raises its own exception classes
        raise TransportError(f"cannot open the {what} ({name}): {type(exc).__name__}: {exc}; "
                             f"{_fd_hint()}") from exc


def _fd_hint() -> str:
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    try:
        used = str(len(os.listdir("/proc/self/fd")))
    except OSError:  # out of descriptors itself, most likely
        used = "all its"
    return (f"this process has {used} files open with a limit of {soft} (hard limit {hard}); "
            "if that is close, raise the limit (ulimit -n) or spread the topics over fewer processes")


def raise_open_file_limit() -> tuple[int, int]:
    """Raise the soft open-file limit to the hard one: each endpoint holds a few descriptors.

    Returns (soft, hard) after the attempt; a hard limit below a few thousand is logged.
    """
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft < hard:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
            soft = hard
        except (ValueError, OSError):
            pass
    if soft < 4096:
        log.warning("the open-file limit is %d (hard limit %d): shared memory needs about 10 file "
                    "descriptors per topic and process, so large graphs may not start; raise it "
                    "with `ulimit -n`", soft, hard)
    return soft, hard


class WakeChannel:
    """Where the readers of one node signal that data may be there: one wait covers them all.

    Publishers notify it with the reader's event id; the node's executor waits on it and
    calls the wake function registered for each id that fired. Event id 0 is the executor's
    own interrupt (an in-process notification or shutdown).
    """

    def __init__(self, node: Any, session: str, owner: str) -> None:
        self.owner = owner
        self.key = _channel_key(session, owner)
        self._service = _event_service(node, wake_channel_name(session, self.key),
                                       f"wake channel of node {owner!r}")
        self._listener = self._service.listener_builder().create()
        self._interrupter = self._service.notifier_builder().create()
        self._routes: dict[int, list[Wake]] = {}
        self._suspects: set[int] = set()
        self._lock = threading.Lock()
        self._ids = itertools.count(0)

    def register(self, wake: Wake) -> int:
        """An event id for one reader; ``wake`` runs (in the waiting thread) when it fires."""
        with self._lock:
            event = next(self._ids) % MAX_EVENT_ID + 1
            self._routes.setdefault(event, []).append(wake)
            return event

    def unregister(self, event: int, wake: Wake) -> None:
        with self._lock:
            routes = self._routes.get(event, [])
            if wake in routes:
                routes.remove(wake)
            self._suspects.discard(event)

    def suspect(self, event: int, suspicious: bool) -> None:
        """A reader saw published samples it could not receive: wake it again soon to recheck."""
        with self._lock:
            if suspicious:
                self._suspects.add(event)
            else:
                self._suspects.discard(event)

    def interrupt(self) -> None:
        self._interrupter.notify_with_custom_event_id(iox2.EventId.new(INTERRUPT_EVENT))

    def wait(self, timeout: float | None) -> None:
        """Block (without the GIL) until an event or ``timeout``; run the wake of each reader that fired."""
        if self._suspects:
            timeout = LOSS_GRACE if timeout is None else min(timeout, LOSS_GRACE)
        if timeout is None:
            fired = self._listener.blocking_wait()
        else:
            fired = self._listener.timed_wait(iox2.Duration.from_secs_f64(max(timeout, 0.0)))
        events = {activation.id.as_value for activation in fired}
        with self._lock:
            events |= self._suspects
            wakes = [wake for e in events for wake in self._routes.get(e, ())]
        for wake in wakes:
            wake()

    def close(self) -> None:
        self._listener = self._interrupter = self._service = None


def wake_channel_name(session: str, key: int) -> str:
    return f"hetros/{session}/wake/{key:016x}"


class ShmDomain:
    """This process' view of the shared-memory fabric of one launch ("session")."""

    def __init__(self, session: str, process_name: str) -> None:
        raise_open_file_limit()
        self.session = session
        self.process_name = process_name
        self._lock = threading.Lock()
        self._node = (
            iox2.NodeBuilder.new()
            .name(iox2.NodeName.new(f"hetros-{session}-{process_name}"[:120]))
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
            .create(iox2.ServiceType.Ipc)
        )
        self._services: dict[str, _Service] = {}
        self._readers: list[ShmReader] = []
        self._channels: dict[str, WakeChannel] = {}
        self._notifiers: dict[int, Any] = {}
        self._back_notifiers: dict[str, Any] = {}
        self._back: _BackChannel | None = None
        self._closed = False

    def _service(self, topic: str, publisher_target: str, qos: QoS) -> _Service:
        key = f"{topic}@{publisher_target}"
        with self._lock:
            service = self._services.get(key)
            if service is None:
                service = _Service(self, self._node, topic, publisher_target, qos)
                self._services[key] = service
            return service

    def wake_channel(self, owner: str) -> WakeChannel:
        """The wake channel of node ``owner`` in this process (created on first use)."""
        with self._lock:
            channel = self._channels.get(owner)
            if channel is None:
                channel = WakeChannel(self._node, self.session, owner)
                self._channels[owner] = channel
            return channel

    def notify(self, key: int, event: int) -> None:
        """Wake reader ``event`` of the node whose wake channel is ``key``."""
        notifier = self._notifiers.get(key)
        if notifier is None:
            service = _event_service(self._node, wake_channel_name(self.session, key), "wake channel of a subscriber")
            notifier = service.notifier_builder().create()
            self._notifiers[key] = notifier
        notifier.notify_with_custom_event_id(iox2.EventId.new(event))

    def notify_back(self, publisher_target: str, event: int) -> None:
        """Tell the publishing process of a service that one of its subscribers took or joined."""
        notifier = self._back_notifiers.get(publisher_target)
        if notifier is None:
            service = _event_service(self._node, back_channel_name(self.session, publisher_target),
                                     f"back channel of target {publisher_target!r}")
            notifier = service.notifier_builder().create()
            self._back_notifiers[publisher_target] = notifier
        notifier.notify_with_custom_event_id(iox2.EventId.new(event))

    def back_channel(self) -> _BackChannel:
        with self._lock:
            if self._back is None:
                self._back = _BackChannel(self._node, self.session, self.process_name)
            return self._back

    def open_writer(self, topic: str, target: str, qos: QoS, codec: Codec, slot: int = 0) -> ShmWriter:
        return ShmWriter(self._service(topic, target, qos), codec, slot)

    def open_reader(
        self,
        topic: str,
        publisher_targets: Sequence[str],
        qos: QoS,
        codec: Codec,
        slot: int,
        wake: Wake,
        owner: str,
    ) -> ShmReader:
        """A reader in subscriber ``slot`` of the topic; ``wake`` runs when ``owner``'s wake channel fires."""
        if not 0 <= slot < MAX_SUBSCRIBER_SLOTS:
            raise TransportError(
                f"subscriber slot of {topic} must be in 0..{MAX_SUBSCRIBER_SLOTS - 1}, not {slot!r}: "
                f"a topic carries at most {MAX_SUBSCRIBER_SLOTS} cross-process subscribers"
            )
        services = [self._service(topic, target, qos) for target in publisher_targets]
        reader = ShmReader(self, services, codec, slot, wake, self.wake_channel(owner))
        self._readers.append(reader)
        return reader

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            services = list(self._services.values())
            self._services.clear()
            back, self._back = self._back, None
        for reader in list(self._readers):
            reader.close()
        self._readers.clear()
        if back is not None:
            back.close()
        for service in services:
            service.close()
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()
        self._notifiers.clear()
        self._back_notifiers.clear()
        # iceoryx2 removes a node's shared memory when its last handle is dropped
        self._node = None


def back_channel_name(session: str, process: str) -> str:
    digest = hashlib.sha1(process.encode()).hexdigest()[:20]
    return f"hetros/{session}/back/{digest}"


class _BackChannel:
    """The publishing process' one back channel and the one thread that watches it.

    Subscribers notify it (with the service's event id) after taking from a FIFO a blocked
    publisher waits on, and when they join; the thread wakes the blocked publisher and
    connects a late joiner so that it receives the history.
    """

    def __init__(self, node: Any, session: str, process: str) -> None:
        self._service = _event_service(node, back_channel_name(session, process), f"back channel of {process!r}")
        self._listener = self._service.listener_builder().create()
        self._interrupter = self._service.notifier_builder().create()
        self._lock = threading.Lock()
        self._services: dict[int, _Service] = {}
        self._ids = itertools.count(1)
        self._closed = False
        self._thread = threading.Thread(target=self._watch, name="hetros-shm-back", daemon=True)
        self._thread.start()

    def register(self, service: _Service) -> int:
        with self._lock:
            event = next(self._ids)
            self._services[event] = service
            return event

    def _watch(self) -> None:
        while not self._closed:
            try:
                fired = self._listener.blocking_wait()
            except Exception:  # iceoryx2's wait failed: nothing left to watch
                return
            with self._lock:
                services = [self._services.get(a.id.as_value) for a in fired]
            for service in services:
                if service is not None:
                    service.subscriber_moved()

    def close(self) -> None:
        self._closed = True
        self._interrupter.notify_with_custom_event_id(iox2.EventId.new(INTERRUPT_EVENT))
        self._thread.join(timeout=2.0)
        self._listener = self._interrupter = self._service = None


class _Service:
    """One (topic, publishing target) service: the data, its credits, and who to wake."""

    def __init__(self, domain: ShmDomain, node: Any, topic: str, target: str, qos: QoS) -> None:
        self.domain = domain
        self.topic = topic
        self.target = target
        self.qos = qos
        digest = hashlib.sha1(f"{topic}@{target}".encode()).hexdigest()[:20]
        base = f"hetros/{domain.session}/{digest}"
        # keep_last: iceoryx2's own overflow keeps exactly the newest `depth`; keep_all: the
        # credits bound the fill at `depth`, the slack absorbs a subscriber's join race.
        self.buffer = qos.depth + 2 if qos.blocks_publisher else qos.depth
        self.blocking = qos.blocks_publisher
        self.room = 0
        self.lock = threading.RLock()
        self.space = threading.Condition(self.lock)
        self._closed = False
        try:
            self.data = (
                node.service_builder(iox2.ServiceName.new(base))
                .publish_subscribe(iox2.Slice[ctypes.c_uint8])
                .max_publishers(MAX_PUBLISHERS_PER_SERVICE)
                .max_subscribers(MAX_SUBSCRIBER_SLOTS)
                .subscriber_max_buffer_size(self.buffer)
                .history_size(qos.depth if qos.keeps_history else 0)
                .enable_safe_overflow(not qos.blocks_publisher)
                .subscriber_max_borrowed_samples(BORROW_LIMIT)
                .open_or_create()
            )
        except Exception as exc:  # iceoryx2 raises its own exception classes
            raise TransportError(
                f"cannot open the shared-memory service of {topic} (publisher target {target!r}): "
                f"{type(exc).__name__}: {exc}; all endpoints of a topic must use the same QoS; {_fd_hint()}"
            ) from exc
        self.credits = Credits(SHM_DIR / f"{segment_prefix(domain.session)}{digest}")
        self._publisher: Any = None
        self._wakes: list[tuple[int, int]] = []
        self._wakes_version = -1
        self.next_seq = 1

    # -- publishing side -------------------------------------------------------------------

    def publisher(self) -> Any:
        with self.lock:
            if self._publisher is None:
                try:
                    self._publisher = (
                        self.data.publisher_builder()
                        .initial_max_slice_len(INITIAL_SLOT)
                        .allocation_strategy(iox2.AllocationStrategy.PowerOfTwo)
                        # hetros' credits do the blocking (with a timeout and crash detection);
                        # iceoryx2's own retry would spin forever on a dead subscriber's full buffer
                        .backpressure_strategy(iox2.BackpressureStrategy.DiscardData)
                        .create()
                    )
                except Exception as exc:  # iceoryx2 raises its own exception classes
                    raise TransportError(f"cannot create a shared-memory publisher on {self.topic}: "
                                         f"{type(exc).__name__}: {exc}; {_fd_hint()}") from exc
                self.credits.back_event = self.domain.back_channel().register(self)
                self.next_seq = self.credits.published + 1
            return self._publisher

    def subscriber_moved(self) -> None:
        """A subscriber took or joined: recount the room, wake a blocked send, send history."""
        with self.lock:
            if self._closed:
                return
            if self.qos.keeps_history and self._publisher is not None:
                self._publisher.update_connections()
            self.room = 0
            self.space.notify_all()

    def wait_for_space(self, deadline: float) -> None:
        """Block (with ``self.lock`` held) until every live blocking subscriber has room."""
        published = self.next_seq - 1
        credits = self.credits
        while True:
            blocked = credits.full_slots(published, self.qos.depth)
            for index in list(blocked):
                _taken, pid = credits.slot(index)
                if not _pid_alive(pid):
                    log.warning(
                        "topic %s: subscriber in process %d is gone (crashed or killed); "
                        "publishing continues without it", self.topic, pid,
                    )
                    credits.leave(index)
                    blocked.remove(index)
            if not blocked:
                credits.waiting = False
                # until this many more sends, no FIFO can fill up: skip the scan until then
                self.room = self.qos.depth - credits.max_fill(published)
                return
            if not credits.waiting:
                credits.waiting = True
                continue  # re-check after announcing: a take may have slipped in between
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                credits.waiting = False
                raise PublishTimeoutError(
                    f"publishing on {self.topic}: the subscriber in process {credits.slot(blocked[0])[1]} "
                    f"kept its FIFO of depth {self.qos.depth} full for {self.qos.publish_timeout:g} s "
                    "(reliable + keep_all blocks the publisher); make the subscriber faster, "
                    "raise 'depth' or 'publish_timeout', or use keep_last"
                )
            if self._closed:
                raise ShutdownError(f"publishing on {self.topic} interrupted by shutdown")
            # short slices: a wake-up lost to store reordering costs at most one slice
            self.space.wait(min(remaining, 0.01))

    def loan(self, size: int) -> tuple[Any, memoryview]:
        """A writable slot of ``size`` payload bytes (header included) and its memory."""
        sample = self.publisher().loan_slice_uninit(size)
        return sample, _slot_memory(sample.payload_ptr, size, sample)

    def send(self, sample: Any, memory: memoryview, layout: int, publisher_slot: int) -> None:
        """Stamp the header and send; blocks first while a reliable keep_all FIFO is full."""
        with self.lock:
            if self.blocking:
                if self.room <= 0:
                    self.wait_for_space(time.monotonic() + self.qos.publish_timeout)
                self.room -= 1
            seq = self.next_seq
            HEADER.pack_into(memory, 0, seq, publisher_slot, layout)
            ready = sample.assume_init()
            try:
                ready.send()
            except iox2.SendError as exc:
                raise TransportError(f"iceoryx2 could not send on {self.topic}: {exc}") from exc
            self.next_seq = seq + 1
            self.credits.published = seq
            credits = self.credits
            if credits.version != self._wakes_version:
                self._wakes_version = credits.version
                self._wakes = credits.subscribers()
            for key, event in self._wakes:
                self.domain.notify(key, event)

    # -- subscribing side ------------------------------------------------------------------

    def subscriber(self, slot: int, channel: WakeChannel, event: int) -> tuple[Any, int]:
        """Join as subscriber ``slot``; returns the port and the last sequence number before the join."""
        try:
            subscriber = self.data.subscriber_builder().buffer_size(self.buffer).create()
        except Exception as exc:  # iceoryx2 raises its own exception classes
            raise TransportError(f"cannot subscribe to {self.topic} in shared memory: "
                                 f"{type(exc).__name__}: {exc}; {_fd_hint()}") from exc
        published = self.credits.published
        # a late joiner's FIFO starts with the history it is about to receive
        start = published - min(published, self.qos.depth) if self.qos.keeps_history else published
        self.credits.join(slot, start, channel.key, event)
        if self.credits.back_event:
            self.domain.notify_back(self.target, self.credits.back_event)
        return subscriber, start

    def close(self) -> None:
        with self.lock:
            self._closed = True
            self.space.notify_all()
        self._publisher = None
        self.data = None
        self.credits.close()


@dataclass
class _Loan:
    sample: Any
    memory: memoryview
    arrays: list[tuple[int, tuple[str, ...], np.ndarray[Any, Any], int]]
    small_at: int


def _without_arrays(message: Any, paths: list[tuple[str, ...]]) -> Any:
    """A shallow copy of ``message`` whose arrays at ``paths`` are empty (the original is untouched)."""

    def shallow(msg: Any) -> Any:
        cls = msg._thawed_class
        clone = cls.__new__(cls)
        for name in cls.__fieldnames__:
            object.__setattr__(clone, name, getattr(msg, name))
        return clone

    root = shallow(message)
    for path in paths:
        holder = root
        for name in path[:-1]:
            child = shallow(getattr(holder, name))
            object.__setattr__(holder, name, child)
            holder = child
        array = getattr(holder, path[-1])
        object.__setattr__(holder, path[-1], array[:0])
    return root


class ShmWriter(Writer):
    """Publishes into one service: arrays go into the slot as blobs (one copy, or none when loaned)."""

    def __init__(self, service: _Service, codec: Codec, slot: int) -> None:
        self._service = service
        self._codec = codec
        self._slot = slot
        self._loans: dict[int, _Loan] = {}
        # variable-length arrays travel as blobs; fixed-size ones stay in the CDR part
        self._arrays = [(index, field) for index, field in enumerate(codec.arrays) if field.length is None] \
            if isinstance(codec, MessageCodec) else []
        service.publisher()

    def write(self, message: Any) -> None:
        loan = self._loans.pop(id(message), None)
        if loan is not None:
            self._send_loan(message, loan)
            return
        size = HEADER.size + self._codec.size(message)
        if self._arrays and size > INLINE_LIMIT:
            # large arrays go as aligned blobs: only the small part needs zeroing
            self._send_copy(message)
            return
        sample, memory = self._service.loan(size)
        # rosbags' serializer leaves terminators and padding to a zeroed buffer
        ctypes.memset(sample.payload_ptr + HEADER.size, 0, size - HEADER.size)
        self._codec.encode_into(message, memory[HEADER.size:])
        self._service.send(sample, memory, LAYOUT_CDR, self._slot)

    def _place(self, plan: list[tuple[int, tuple[str, ...], np.dtype[Any], int]], reserve: int
               ) -> tuple[Any, memoryview, int, list[tuple[int, tuple[str, ...], np.ndarray[Any, Any], int]]]:
        """A slot with room for the small part and 64-byte aligned blobs; views on the blobs."""
        table_end = HEADER.size + SPLIT.size + BLOB.size * len(plan)
        small_at = _align(table_end, 8) + 4
        offset = _align(small_at + reserve, 64)
        offsets = []
        for _index, _path, dtype, length in plan:
            offsets.append(offset)
            offset = _align(offset + length * dtype.itemsize, 64)
        sample, memory = self._service.loan(offset)
        views = [(index, path, np.frombuffer(memory, dtype=dtype, count=length, offset=at), at)
                 for (index, path, dtype, length), at in zip(plan, offsets, strict=True)]
        return sample, memory, small_at, views

    def _send_copy(self, message: Any) -> None:
        plan = []
        for index, field in self._arrays:
            array = np.asarray(get_path(message, field.path))
            if array.size:
                plan.append((index, field.path, field.dtype, int(array.size)))
        reserve = self._codec.size(_without_arrays(message, [path for _i, path, _d, _n in plan]))
        sample, memory, small_at, views = self._place(plan, reserve)
        for _index, path, view, _at in views:
            np.copyto(view, get_path(message, path), casting="unsafe")
        self._finish(message, _Loan(sample, memory, views, small_at))

    def loan(self, sizes: dict[str, int]) -> Any:
        """A message whose primitive arrays live in a shared-memory slot (zero-copy publish)."""
        codec = self._codec
        if not isinstance(codec, MessageCodec):
            raise TransportError("only topic messages can be loaned")
        wanted = dict(sizes)
        plan: list[tuple[int, tuple[str, ...], np.dtype[Any], int]] = []
        for index, field in self._arrays:
            length = wanted.pop(".".join(field.path), 0)
            if length:
                plan.append((index, field.path, field.dtype, length))
        if wanted:
            known = ", ".join(".".join(f.path) for _i, f in self._arrays) or "none"
            raise TransportError(
                f"{codec.typename} has no variable-length primitive array {', '.join(wanted)!s}; "
                f"loan sizes can be given for: {known}"
            )
        sample, memory, small_at, views = self._place(plan, LOAN_RESERVE)
        message = codec.cls()
        for _index, path, view, _at in views:
            set_path(message, path, view)
        self._loans[id(message)] = _Loan(sample, memory, views, small_at)
        return message

    def _send_loan(self, message: Any, loan: _Loan) -> None:
        for _index, path, array, _at in loan.arrays:
            current = get_path(message, path)
            if current is array:
                continue
            if not isinstance(current, np.ndarray) or current.size != array.size:
                # the node replaced a loaned array with one of another size: send a plain copy
                loan.arrays.clear()
                self._send_copy(message)
                return
            np.copyto(array, current, casting="unsafe")
        self._finish(message, loan)
        for _index, path, array, _at in loan.arrays:
            set_path(message, path, array[:0].copy())

    def _finish(self, message: Any, loan: _Loan) -> None:
        """Encode the small part, write the blob table and send the slot."""
        codec = self._codec
        memory = loan.memory
        small_message = _without_arrays(message, [path for _i, path, _a, _at in loan.arrays])
        small = codec.size(small_message)
        if small > LOAN_RESERVE:
            raise TransportError(
                f"{getattr(codec, 'typename', 'message')}: {small} bytes besides its arrays exceed the "
                f"{LOAN_RESERVE}-byte reserve of a shared-memory slot; shorten its strings"
            )
        memory[loan.small_at:loan.small_at + small] = bytes(small)
        codec.encode_into(small_message, memory[loan.small_at:loan.small_at + small])
        SPLIT.pack_into(memory, HEADER.size, small, len(loan.arrays))
        for position, (index, _path, array, at) in enumerate(loan.arrays):
            BLOB.pack_into(memory, HEADER.size + SPLIT.size + BLOB.size * position, index, loan.small_at,
                           at, array.nbytes)
        self._service.send(loan.sample, memory, LAYOUT_SPLIT, self._slot)

    def close(self) -> None:
        self._loans.clear()


class _Borrowed:
    """Counts a reader's samples still referenced by delivered messages."""

    __slots__ = ("count", "lock")

    def __init__(self) -> None:
        self.count = 0
        self.lock = threading.Lock()


class _Lease:
    """Holds a received sample; it goes back to the publisher when no message refers to it."""

    __slots__ = ("borrowed", "sample")

    def __init__(self, sample: Any, borrowed: _Borrowed) -> None:
        self.sample = sample
        self.borrowed = borrowed
        with borrowed.lock:
            borrowed.count += 1

    def __del__(self) -> None:
        with self.borrowed.lock:
            self.borrowed.count -= 1


def _frozen(item: Any) -> Any:
    """What a reader delivers is read-only: a message, or the message of a service envelope."""
    if isinstance(item, Message):
        freeze(item)
    elif isinstance(item, tuple) and item and isinstance(item[-1], Message):
        freeze(item[-1])
    return item


class _Port:
    """One publishing target's service as seen by one reader."""

    __slots__ = ("expected", "service", "subscriber", "suspect_since")

    def __init__(self, service: _Service, subscriber: Any, start: int) -> None:
        self.service = service
        self.subscriber = subscriber
        self.expected = start + 1
        self.suspect_since = 0.0


class ShmReader(Reader):
    """Takes from every publishing target's service of one topic.

    Delivered primitive arrays are read-only views on the shared-memory slot; the slot
    is returned when the last of them is gone (``msg.copy()`` keeps data longer).
    """

    def __init__(self, domain: ShmDomain, services: list[_Service], codec: Codec, slot: int, wake: Wake,
                 channel: WakeChannel) -> None:
        self._domain = domain
        self._codec = codec
        self._slot = slot
        self._closed = False
        self._channel = channel
        self._wake = wake
        self.event = channel.register(wake)
        self._ports: list[_Port] = []
        self._next = 0
        self._lock = threading.Lock()
        self._borrowed = _Borrowed()
        self.topic = services[0].topic if services else ""
        for service in services:
            subscriber, start = service.subscriber(slot, channel, self.event)
            self._ports.append(_Port(service, subscriber, start))
        wake()

    # -- taking ----------------------------------------------------------------------------

    def try_take(self) -> Any | None:
        with self._lock:
            for _ in range(len(self._ports)):
                port = self._ports[self._next]
                self._next = (self._next + 1) % len(self._ports)
                service = port.service
                sample = port.subscriber.receive()
                if sample is None:
                    if service.blocking:
                        self._check_arrival(port)
                    continue
                size = sample.header.number_of_elements
                memory = _slot_memory(sample.payload_ptr, size, _Lease(sample, self._borrowed))
                del sample
                seq, _publisher_slot, layout = HEADER.unpack_from(memory, 0)
                if service.blocking and seq != port.expected and seq > port.expected:
                    self._lost(port, seq - port.expected)
                port.expected = seq + 1
                if port.suspect_since:
                    port.suspect_since = 0.0
                    self._channel.suspect(self.event, False)
                credits = service.credits
                credits.set_taken(self._slot, seq)
                if service.blocking and credits.waiting:
                    self._domain.notify_back(service.target, credits.back_event)
                if self._borrowed.count >= BORROW_LIMIT - 2:
                    memory = memoryview(bytes(memory))
                return _frozen(self._decode(memory.toreadonly(), layout))
            return None

    def _check_arrival(self, port: _Port) -> None:
        """Nothing to receive: is that true, or did iceoryx2 fail to connect to the publisher?"""
        published = port.service.credits.published
        if published < port.expected:
            if port.suspect_since:
                port.suspect_since = 0.0
                self._channel.suspect(self.event, False)
            return
        now = time.monotonic()
        if not port.suspect_since:
            port.suspect_since = now
            self._channel.suspect(self.event, True)
        elif now - port.suspect_since > LOSS_GRACE:
            self._lost(port, published - port.expected + 1)

    def _lost(self, port: _Port, count: int) -> None:
        raise TransportError(
            f"reliable topic {port.service.topic}: {count} message(s) from target {port.service.target!r} "
            f"(from #{port.expected}) never reached this subscriber although the publisher sent them; "
            f"iceoryx2 could not deliver them, most often because a process ran out of file descriptors "
            f"({_fd_hint()})"
        )

    def _decode(self, memory: memoryview, layout: int) -> Any:
        if layout == LAYOUT_CDR:
            return self._codec.decode(memory[HEADER.size:])
        if layout != LAYOUT_SPLIT or not isinstance(self._codec, MessageCodec):
            raise SerializationError(f"unknown shared-memory layout {layout} at offset 12 of the sample header")
        small, count = SPLIT.unpack_from(memory, HEADER.size)
        arrays = self._codec.arrays
        blobs = [BLOB.unpack_from(memory, HEADER.size + SPLIT.size + BLOB.size * i) for i in range(count)]
        small_at = blobs[0][1] if blobs else _align(HEADER.size + SPLIT.size, 8) + 4
        message = self._codec.decode(memory[small_at:small_at + small])
        for index, _small_at, offset, nbytes in blobs:
            if index >= len(arrays) or offset + nbytes > len(memory):
                raise SerializationError(
                    f"blob {index} at offset {offset} ({nbytes} bytes) does not fit a "
                    f"{len(memory)}-byte sample of {self._codec.typename}"
                )
            field = arrays[index]
            view = np.frombuffer(memory, dtype=field.dtype, count=nbytes // field.dtype.itemsize, offset=offset)
            set_path(message, field.path, view)
        return message

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._channel.unregister(self.event, self._wake)
        for port in self._ports:
            port.service.credits.leave(self._slot)
        self._ports.clear()


def remove_session_segments(session: str) -> list[str]:
    """Unlink every credits file of a session (the launcher calls it on the way out)."""
    removed: list[str] = []
    for path in SHM_DIR.glob(f"{segment_prefix(session)}*"):
        _unlink(path, removed)
    return removed


def _unlink(path: Path, removed: list[str]) -> None:
    try:
        path.unlink()
        removed.append(path.name)
    except FileNotFoundError:
        pass


def cleanup_stale() -> list[str]:
    """Remove what crashed launches left: dead iceoryx2 nodes and orphaned credits files."""
    removed: list[str] = []
    try:
        states = iox2.Node.list(iox2.ServiceType.Ipc, iox2.config.global_config())
    except Exception:
        states = []
    for state in states:
        if type(state).__name__ != "Dead":
            continue
        view = state._0
        details = view.details
        if details is None or not details.name.as_str().startswith("hetros-"):
            continue
        try:
            view.try_remove_stale_resources()
            removed.append(details.name.as_str())
        except Exception:
            pass
    for path in SHM_DIR.glob("hetros-*"):
        owner = path.name.split("-")[1].split("x")[0] if path.name.count("-") >= 2 else ""
        if owner.isdigit() and not _pid_alive(int(owner)):
            _unlink(path, removed)
    return removed
