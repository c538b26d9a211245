"""Same-host, cross-process transport on iceoryx2 shared memory.

Layout, fixed by the static plan (no discovery at run time):

* one iceoryx2 publish-subscribe service per (topic, publishing target), so a
  process never receives through shared memory what it already delivered to
  itself in-process; all publishers of a service live in one process;
* one iceoryx2 event service beside it that wakes subscribers (no polling),
  and a back-channel event service that wakes blocked publishers;
* a small *credits* file in /dev/shm per service: the sequence number last
  published and, per subscriber slot, the sequence it last took and its pid.
  A reliable keep_all publisher computes each subscriber's fill level from it
  and blocks while a FIFO holds ``depth`` messages: back-pressure across
  processes, with a timeout and with crashed subscribers detected by pid.

Every sample starts with a 16-byte header (sequence number, publisher slot,
reserved); the message follows in the codec's format (CDR for messages).
"""

from __future__ import annotations

import ctypes
import hashlib
import logging
import mmap
import os
import struct
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from .._errors import PublishTimeoutError, ShutdownError, TransportError
from ._base import Codec, Reader, Wake, Writer
from ._qos import QoS

os.environ.setdefault("IOX2_LOG_LEVEL", "Error")
import iceoryx2 as iox2

iox2.set_log_level(iox2.LogLevel.Error)

log = logging.getLogger("hetros.transport.shm")

SHM_DIR = Path("/dev/shm")
HEADER = struct.Struct("<QII")
CREDIT = struct.Struct("<QQ")
MAX_SUBSCRIBER_SLOTS = 32
MAX_PUBLISHERS_PER_SERVICE = 8
MAX_EVENT_PORTS = 64
_PUBLISHED = struct.Struct("<Q")


def segment_prefix(session: str) -> str:
    return f"hetros-{session}-"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class Credits:
    """The credits file of one service: ``published`` then (taken, pid) per subscriber slot."""

    SIZE = _PUBLISHED.size + CREDIT.size * MAX_SUBSCRIBER_SLOTS

    def __init__(self, path: Path) -> None:
        self.path = path
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
        try:
            if os.fstat(fd).st_size < self.SIZE:
                os.ftruncate(fd, self.SIZE)
            self._map = mmap.mmap(fd, self.SIZE)
        finally:
            os.close(fd)

    @property
    def published(self) -> int:
        return int(_PUBLISHED.unpack_from(self._map, 0)[0])

    @published.setter
    def published(self, seq: int) -> None:
        _PUBLISHED.pack_into(self._map, 0, seq)

    def slot(self, index: int) -> tuple[int, int]:
        taken, pid = CREDIT.unpack_from(self._map, _PUBLISHED.size + CREDIT.size * index)
        return int(taken), int(pid)

    def set_slot(self, index: int, taken: int, pid: int) -> None:
        CREDIT.pack_into(self._map, _PUBLISHED.size + CREDIT.size * index, taken, pid)

    def set_taken(self, index: int, taken: int) -> None:
        struct.pack_into("<Q", self._map, _PUBLISHED.size + CREDIT.size * index, taken)

    def close(self) -> None:
        try:
            self._map.close()
        except BufferError:
            pass


class ShmDomain:
    """This process' view of the shared-memory fabric of one launch ("session")."""

    def __init__(self, session: str, process_name: str) -> None:
        self.session = session
        self._lock = threading.Lock()
        self._node = (
            iox2.NodeBuilder.new()
            .name(iox2.NodeName.new(f"hetros-{session}-{process_name}"[:120]))
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
            .create(iox2.ServiceType.Ipc)
        )
        self._services: dict[str, _Service] = {}
        self._closed = False

    def _service(self, topic: str, publisher_target: str, qos: QoS) -> _Service:
        key = f"{topic}@{publisher_target}"
        with self._lock:
            service = self._services.get(key)
            if service is None:
                service = _Service(self, self._node, topic, publisher_target, qos)
                self._services[key] = service
            return service

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
    ) -> ShmReader:
        if not 0 <= slot < MAX_SUBSCRIBER_SLOTS:
            raise TransportError(
                f"subscriber slot of {topic} must be in 0..{MAX_SUBSCRIBER_SLOTS - 1}, not {slot!r}: "
                f"a topic carries at most {MAX_SUBSCRIBER_SLOTS} cross-process subscribers"
            )
        services = [self._service(topic, target, qos) for target in publisher_targets]
        return ShmReader(services, codec, slot, wake)

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            services = list(self._services.values())
            self._services.clear()
        for service in services:
            service.close()
        del self._node


class _Service:
    """One (topic, publishing target) service: data, wake-up and back-channel events."""

    def __init__(self, domain: ShmDomain, node: Any, topic: str, target: str, qos: QoS) -> None:
        self.topic = topic
        self.target = target
        self.qos = qos
        digest = hashlib.sha1(f"{topic}@{target}".encode()).hexdigest()[:20]
        base = f"hetros/{domain.session}/{digest}"
        # keep_last: iceoryx2's own overflow keeps exactly the newest `depth`; keep_all: the
        # credits bound the fill at `depth`, the slack only absorbs a subscriber's join race.
        self.buffer = qos.depth + 2 if qos.blocks_publisher else qos.depth
        self.lock = threading.RLock()
        self.space = threading.Condition(self.lock)
        self._closed = False
        try:
            builder = (
                node.service_builder(iox2.ServiceName.new(base))
                .publish_subscribe(iox2.Slice[ctypes.c_uint8])
                .max_publishers(MAX_PUBLISHERS_PER_SERVICE)
                .max_subscribers(MAX_SUBSCRIBER_SLOTS)
                .subscriber_max_buffer_size(self.buffer)
                .history_size(qos.depth if qos.keeps_history else 0)
                .enable_safe_overflow(not qos.blocks_publisher)
            )
            self.data = builder.open_or_create()
            self.wakeup = (
                node.service_builder(iox2.ServiceName.new(base + "/wake")).event()
                .max_listeners(MAX_EVENT_PORTS).max_notifiers(MAX_EVENT_PORTS).open_or_create()
            )
            self.back = (
                node.service_builder(iox2.ServiceName.new(base + "/back")).event()
                .max_listeners(MAX_EVENT_PORTS).max_notifiers(MAX_EVENT_PORTS).open_or_create()
            )
        except Exception as exc:  # iceoryx2 raises its own exception classes
            raise TransportError(
                f"cannot open the shared-memory service of {topic} (publisher target {target!r}): "
                f"{type(exc).__name__}: {exc}; all endpoints of a topic must use the same QoS"
            ) from exc
        self.credits = Credits(SHM_DIR / f"{segment_prefix(domain.session)}{digest}")
        self._publisher: Any = None
        self._notifier: Any = None
        self._back_notifier: Any = None
        self._watcher: threading.Thread | None = None
        self._back_listener: Any = None
        self.next_seq = 1

    # -- publishing side -------------------------------------------------------------------

    def publisher(self) -> Any:
        with self.lock:
            if self._publisher is None:
                self._publisher = (
                    self.data.publisher_builder()
                    .initial_max_slice_len(4096)
                    .allocation_strategy(iox2.AllocationStrategy.PowerOfTwo)
                    .create()
                )
                self._notifier = self.wakeup.notifier_builder().create()
                self._back_listener = self.back.listener_builder().create()
                self._back_notifier_self = self.back.notifier_builder().create()
                self.next_seq = self.credits.published + 1
                self._watcher = threading.Thread(
                    target=self._watch_back_channel, name=f"hetros-shm-back{self.topic}", daemon=True
                )
                self._watcher.start()
            return self._publisher

    def _watch_back_channel(self) -> None:
        """Wake blocked publishers when a subscriber takes; connect late joiners."""
        listener = self._back_listener
        while not self._closed:
            try:
                listener.blocking_wait()
            except Exception:
                return
            with self.lock:
                if self._closed:
                    return
                if self.qos.keeps_history and self._publisher is not None:
                    self._publisher.update_connections()
                self.space.notify_all()

    def wait_for_space(self, deadline: float, publisher_slot: int) -> None:
        """Block (with ``self.lock`` held) until every live blocking subscriber has room."""
        seq_before = self.next_seq - 1
        while True:
            full: tuple[int, int] | None = None
            for index in range(MAX_SUBSCRIBER_SLOTS):
                taken, pid = self.credits.slot(index)
                if pid == 0 or seq_before - taken < self.qos.depth:
                    continue
                if not _pid_alive(pid):
                    log.warning(
                        "topic %s: subscriber in process %d is gone (crashed or killed); "
                        "publishing continues without it", self.topic, pid,
                    )
                    self.credits.set_slot(index, 0, 0)
                    continue
                full = (index, pid)
                break
            if full is None:
                return
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise PublishTimeoutError(
                    f"publishing on {self.topic}: the subscriber in process {full[1]} kept its FIFO "
                    f"of depth {self.qos.depth} full for {self.qos.publish_timeout:g} s "
                    "(reliable + keep_all blocks the publisher); make the subscriber faster, "
                    "raise 'depth' or 'publish_timeout', or use keep_last"
                )
            if self._closed:
                raise ShutdownError(f"publishing on {self.topic} interrupted by shutdown")
            self.space.wait(min(remaining, 0.1))

    def send(self, size: int, fill: Callable[[memoryview], None], publisher_slot: int) -> None:
        with self.lock:
            publisher = self.publisher()
            if self.qos.blocks_publisher:
                self.wait_for_space(time.monotonic() + self.qos.publish_timeout, publisher_slot)
            seq = self.next_seq
            sample = publisher.loan_slice_uninit(HEADER.size + size)
            view = memoryview(
                (ctypes.c_uint8 * (HEADER.size + size)).from_address(sample.payload_ptr)
            ).cast("B")
            HEADER.pack_into(view, 0, seq, publisher_slot, 0)
            fill(view[HEADER.size:])
            view.release()
            sample.assume_init().send()
            self.next_seq = seq + 1
            self.credits.published = seq
            self._notifier.notify()

    # -- subscribing side ------------------------------------------------------------------

    def subscriber(self, slot: int) -> tuple[Any, Any, Any]:
        subscriber = self.data.subscriber_builder().buffer_size(self.buffer).create()
        self.credits.set_slot(slot, self.credits.published, os.getpid())
        listener = self.wakeup.listener_builder().create()
        back = self.back.notifier_builder().create()
        back.notify()
        return subscriber, listener, back

    def close(self) -> None:
        with self.lock:
            self._closed = True
            self.space.notify_all()
            if self._publisher is not None:
                self._back_notifier_self.notify()
        if self._watcher is not None:
            self._watcher.join(timeout=2.0)
        self._publisher = None
        self.credits.close()


class ShmWriter(Writer):
    def __init__(self, service: _Service, codec: Codec, slot: int) -> None:
        self._service = service
        self._codec = codec
        self._slot = slot
        service.publisher()

    def write(self, message: Any) -> None:
        codec = self._codec
        self._service.send(codec.size(message), lambda view: codec.encode_into(message, view), self._slot)

    def close(self) -> None:
        return None


class ShmReader(Reader):
    """Takes from every publishing target's service of one topic; one waiter thread each."""

    def __init__(self, services: list[_Service], codec: Codec, slot: int, wake: Wake) -> None:
        self._codec = codec
        self._slot = slot
        self._wake = wake
        self._closed = False
        self._ports: list[tuple[_Service, Any, Any, Any]] = []
        self._threads: list[threading.Thread] = []
        self._next = 0
        self._lock = threading.Lock()
        for service in services:
            subscriber, listener, back = service.subscriber(slot)
            self._ports.append((service, subscriber, listener, back))
            thread = threading.Thread(
                target=self._wait, args=(listener,), name=f"hetros-shm-wait{service.topic}", daemon=True
            )
            self._threads.append(thread)
        for thread in self._threads:
            thread.start()
        self._wake()

    def _wait(self, listener: Any) -> None:
        while not self._closed:
            try:
                listener.blocking_wait()
            except Exception:
                return
            if not self._closed:
                self._wake()

    def try_take(self) -> Any | None:
        with self._lock:
            for _ in range(len(self._ports)):
                service, subscriber, _listener, back = self._ports[self._next]
                self._next = (self._next + 1) % len(self._ports)
                sample = subscriber.receive()
                if sample is None:
                    continue
                payload = sample.payload()
                data = bytes(payload.as_memory_view())
                del payload
                sample.delete()
                seq, _publisher_slot, _ = HEADER.unpack_from(data, 0)
                taken, _pid = service.credits.slot(self._slot)
                service.credits.set_taken(self._slot, max(taken, seq))
                if service.qos.blocks_publisher:
                    back.notify()
                return self._codec.decode(memoryview(data)[HEADER.size:])
            return None

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        for service, _subscriber, _listener, _back in self._ports:
            service.credits.set_slot(self._slot, 0, 0)
            notifier = service.wakeup.notifier_builder().create()
            notifier.notify()
            del notifier
        for thread in self._threads:
            thread.join(timeout=2.0)
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
