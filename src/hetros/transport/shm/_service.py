"""One (topic, publishing target) service: its data, its credits and who to wake."""

from __future__ import annotations

import ctypes
import os
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..._errors import PublishTimeoutError, ShutdownError, TransportError
from ..._process import pid_alive
from ..._qos import QoS
from .._codec import CDR_LE
from ._credits import Credits
from ._events import (
    WakeChannel,
    fd_hint,
)
from ._hotpath import SENT_STALE_WAKES, bind_slots, send_cdr, send_slot
from ._iceoryx import assume_init, iox2, loan_slice, log, sha1
from ._sample import (
    BORROW_LIMIT,
    CDR_BODY_AT,
    HEADER,
    INITIAL_SLOT,
    LAYOUT_CDR,
    MAX_LOANS,
    MAX_PUBLISHERS_PER_SERVICE,
    MAX_SUBSCRIBER_SLOTS,
    SHM_DIR,
    ScratchViews,
    check_room,
    remove_unfinished_segments,
    reserved_bytes,
    segment_prefix,
    slot_memory,
)

if TYPE_CHECKING:
    from ._domain import ShmDomain

# how long a publisher facing a full reliable FIFO re-reads the credits awake before it blocks
FULL_SPIN = 100e-6


class Service:
    """One (topic, publishing target) service: the data, its credits, and who to wake."""

    # slots, which the compiled send path reads and writes in place (``_hotpath.bind_slots``)
    __slots__ = ("_closed", "_publisher", "_scratch", "_wakes", "_wakes_version", "blocking", "buffer", "credits",
                 "credits_at", "data", "domain", "lock", "next_seq", "qos", "repaired", "room", "space", "stalls",
                 "target", "topic")

    def __init__(self, domain: ShmDomain, node: Any, topic: str, target: str, qos: QoS) -> None:
        self.domain = domain
        self.topic = topic
        self.target = target
        self.qos = qos
        digest = sha1(f"{topic}@{target}".encode()).hexdigest()[:20]
        base = f"hetros/{domain.session}/{digest}"
        # keep_last: iceoryx2's own overflow keeps exactly the newest `depth`; keep_all: the
        # credits bound the fill at `depth`, the slack absorbs a subscriber's join race.
        self.buffer = qos.depth + 2 if qos.blocks_publisher else qos.depth
        self.blocking = qos.blocks_publisher
        self.room = 0
        self.lock = threading.Lock()
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
                f"{type(exc).__name__}: {exc}; all endpoints of a topic must use the same QoS; {fd_hint()}"
            ) from exc
        self.credits = Credits(SHM_DIR / f"{segment_prefix(domain.session)}{digest}")
        # where the compiled hot path finds the credits words; 0 once they are unmapped
        self.credits_at = int(self.credits.words.ctypes.data)
        self._publisher: Any = None
        self._scratch = ScratchViews()
        self._wakes: list[tuple[Any, Any]] = []
        self._wakes_version = -1
        self.next_seq = 1
        self.stalls = 0  # sends that had to wait for a reliable subscriber's room (hetros top)
        self.repaired = 0  # credits slots set right after another process damaged them

    # -- publishing side -------------------------------------------------------------------

    def publisher(self) -> Any:
        with self.lock:
            if self._publisher is None:
                check_room(reserved_bytes(self.qos, None), f"the shared-memory publisher of {self.topic}")
                try:
                    self._publisher = (
                        self.data.publisher_builder()
                        .initial_max_slice_len(INITIAL_SLOT)
                        .max_loaned_samples(MAX_LOANS)
                        .allocation_strategy(iox2.AllocationStrategy.PowerOfTwo)
                        # hetros' credits do the blocking (with a timeout and crash detection);
                        # iceoryx2's own retry would spin forever on a dead subscriber's full buffer
                        .backpressure_strategy(iox2.BackpressureStrategy.DiscardData)
                        .create()
                    )
                except Exception as exc:  # iceoryx2 raises its own exception classes
                    raise TransportError(f"cannot create a shared-memory publisher on {self.topic}: "
                                         f"{type(exc).__name__}: {exc}; {fd_hint()}") from exc
                self.credits.back_event = self.domain.back_channel().register(self)
                self.credits.publisher_pid = os.getpid()
                self.next_seq = self.credits.published + 1
            return self._publisher

    def behind(self) -> list[tuple[int, int, int]]:
        """(slot, pid, count) of each live subscriber that has not taken everything this process
        published reliably: what would be lost if the process ended now. Subscribers whose
        process is gone are let go."""
        if self._publisher is None or self.qos.reliability != "reliable":
            return []
        credits = self.credits
        behind = []
        for slot, pid, count in credits.behind(self.next_seq - 1):
            if pid_alive(pid):
                behind.append((slot, pid, count))
            else:
                credits.leave(slot)
        return behind

    def subscriber_moved(self) -> None:
        """A subscriber took or joined: recount the room, wake a blocked send, send history."""
        with self.lock:
            if self._closed:
                return
            if self.qos.keeps_history and self._publisher is not None:
                self._publisher.update_connections()
            self.room = 0
            self.space.notify_all()

    def has_room(self) -> bool:
        """Whether a send now would not wait: every live blocking subscriber has room (a dead one is
        removed by the send, which then goes on)."""
        if not self.blocking:
            return True
        with self.lock:
            if self.room > 0:
                return True
            published = self.next_seq - 1
            credits = self.credits
            self._repair(published)
            blocked = credits.full_slots(published, self.qos.depth)
            if any(not pid_alive(credits.slot(index)[1]) for index in blocked):
                return True
            if blocked:
                return False
            self.room = self.qos.depth - credits.max_fill(published)
            return True

    def _repair(self, published: int) -> None:
        """Words of the credits file no subscriber could have written (another process of this user
        wrote them) are set right before they decide whether this publisher waits; counted and told."""
        repaired = self.credits.repair(published, self.buffer)
        if repaired:
            self.repaired += repaired
            log.warning("topic %s: the credits file held %d subscriber slot(s) no subscriber could have written "
                        "(another process changed %s); set right, %d so far", self.topic, repaired,
                        self.credits.path, self.repaired)

    def wait_for_space(self, deadline: float) -> None:
        """Block (with ``self.lock`` held) until every live blocking subscriber has room.

        A subscriber that keeps up frees room within microseconds: the publisher re-reads
        the credits awake for ``FULL_SPIN`` before it announces that it waits and blocks
        (being woken costs the subscriber a notification and this process two thread
        wake-ups; at 64 B that was 10-15 % of the throughput).
        """
        published = self.next_seq - 1
        credits = self.credits
        spin_until: float | None = None
        self._repair(published)
        while True:
            blocked = credits.full_slots(published, self.qos.depth)
            for index in list(blocked):
                _taken, pid = credits.slot(index)
                if not pid_alive(pid):
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
                if spin_until is None:
                    spin_until = time.perf_counter() + FULL_SPIN
                if time.perf_counter() < spin_until:
                    os.sched_yield()
                    continue
                credits.waiting = True
                self.stalls += 1
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
        """A writable slot of ``size`` payload bytes (header included) and its memory.

        The memory keeps the slot's sample alive: views of it may outlive the call (loans).
        """
        sample = self._loan_sample(size)
        return sample, slot_memory(sample.payload_ptr, size, sample)

    def loan_scratch(self, size: int) -> tuple[Any, memoryview]:
        """A slot as ``loan`` gives it, its memory a view to fill now and drop before ``send``.

        The view does not hold the sample, so one per slot address is kept and reused: the
        inline path writes the message and sends, and nothing else sees the view. It may be
        longer than ``size`` (made for a larger message in the same slot); only the first
        ``size`` bytes are this sample's.
        """
        sample = self._loan_sample(size)
        return sample, self._scratch.at(sample.payload_ptr, size)

    def send_cdr(self, message: Any, body_size: int, encode_body: Callable[[Any, memoryview, int], object],
                 publisher_slot: int) -> None:
        """The inline path as one call (the hot path of small messages): a slot, the message
        in it as ``LAYOUT_CDR`` (encapsulation, then the body ``encode_body`` writes), sent."""
        if send_cdr is not None and self._publisher is not None:
            lock = self.lock
            lock.acquire()  # not ``with``: once per small message, and ``with`` costs 0.08 µs more
            try:
                status = send_cdr(self, message, body_size, encode_body, publisher_slot)
                if status == SENT_STALE_WAKES:
                    self._wake_subscribers(self.credits.version)
            except iox2.LoanError as exc:
                raise self._no_slot(CDR_BODY_AT + body_size, exc) from exc
            except iox2.SendError as exc:
                raise self._not_sent(exc) from exc
            finally:
                lock.release()
            if status:
                return
        # without the compiled path, or what it leaves (no publisher yet, a full FIFO to wait for)
        sample = self._loan_sample(CDR_BODY_AT + body_size)
        memory = self._scratch.at(sample.payload_ptr, CDR_BODY_AT + body_size)
        memory[HEADER.size:CDR_BODY_AT] = CDR_LE
        encode_body(message, memory, CDR_BODY_AT)
        self.send(sample, memory, LAYOUT_CDR, publisher_slot)

    def _loan_sample(self, size: int) -> Any:
        try:
            return loan_slice(self._publisher or self.publisher(), size)
        except iox2.LoanError as exc:
            raise self._no_slot(size, exc) from exc

    def _no_slot(self, size: int, exc: Exception) -> TransportError:
        if "MaxLoans" in str(exc):  # iceoryx2's ExceedsMaxLoans: the loans are the cause
            return TransportError(
                f"cannot take a shared-memory slot of {size} bytes on {self.topic} ({exc}): a publisher holds "
                f"at most {MAX_LOANS} unpublished loans at once; publish the loaned messages you hold, or "
                "drop them (a dropped loan returns its slot when the message is garbage-collected)"
            )
        # a growth that failed leaves its unfinished segment behind (sparse, the size asked for)
        remove_unfinished_segments(larger_than=size)
        return TransportError(
            f"cannot take a shared-memory slot of {size} bytes on {self.topic} ({exc}): iceoryx2 could not make "
            "room for it; shared memory (/dev/shm, or the memory limit of this process or its cgroup) is most "
            "likely full: free some, raise the limit, or send smaller messages"
        )

    def _not_sent(self, exc: Exception) -> TransportError:
        return TransportError(f"iceoryx2 could not send on {self.topic}: {exc}")

    def send(self, sample: Any, memory: memoryview, layout: int, publisher_slot: int) -> None:
        """Stamp the header and send; blocks first while a reliable keep_all FIFO is full."""
        if send_slot is not None and self._publisher is not None:
            with self.lock:
                try:
                    status = send_slot(self, sample, layout, publisher_slot)
                except iox2.SendError as exc:
                    raise self._not_sent(exc) from exc
                if status == SENT_STALE_WAKES:
                    self._wake_subscribers(self.credits.version)
            if status:
                return
        with self.lock:
            if self.blocking:
                if self.room <= 0:
                    self.wait_for_space(time.monotonic() + self.qos.publish_timeout)
                self.room -= 1
            seq = self.next_seq
            HEADER.pack_into(memory, 0, seq, publisher_slot, layout, time.monotonic_ns())
            try:
                assume_init(sample).send()
            except iox2.SendError as exc:
                raise self._not_sent(exc) from exc
            self.next_seq = seq + 1
            self._wake_subscribers(self.credits.publish(seq))

    def _wake_subscribers(self, version: int) -> None:
        """Notify every subscriber, after rereading who they are if ``version`` says they changed."""
        if version != self._wakes_version:
            self._wakes_version = version
            restored = self.credits.restored
            self._wakes = [self.domain.notifier(key, event)
                           for key, event in self.credits.subscribers(self.next_seq - 1)]
            if self.credits.restored != restored:
                log.warning("topic %s: %d subscriber slot(s) of %s were overwritten by another process; written "
                            "back from this publisher's copy (%d so far)", self.topic,
                            self.credits.restored - restored, self.credits.path, self.credits.restored)
        for notify, event_id in self._wakes:
            notify(event_id)

    # -- subscribing side ------------------------------------------------------------------

    def subscriber(self, slot: int, channel: WakeChannel, event: int) -> tuple[Any, int]:
        """Join as subscriber ``slot``; returns the port and the last sequence number before the join."""
        try:
            subscriber = self.data.subscriber_builder().buffer_size(self.buffer).create()
        except Exception as exc:  # iceoryx2 raises its own exception classes
            raise TransportError(f"cannot subscribe to {self.topic} in shared memory: "
                                 f"{type(exc).__name__}: {exc}; {fd_hint()}") from exc
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
        self._scratch.clear()
        self._wakes = []  # they hold notifiers, and so other nodes' event services
        self.data = None
        self.credits_at = 0
        self.credits.close()


bind_slots(Service, ("_publisher", "credits_at", "blocking", "room", "next_seq", "_wakes_version", "_wakes",
                     "qos"))
