"""Writers and readers of one shared-memory topic."""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..._errors import SerializationError, TransportError
from ..._process import pid_alive
from ...msg import default_maker, get_path, set_path
from .._base import Codec, Reader, Wake, Writer
from .._codec import MessageCodec
from ._events import (
    WakeChannel,
    fd_hint,
)
from ._hotpath import bind_slots, take_cdr
from ._iceoryx import iox2, log
from ._sample import (
    BLOB,
    BORROW_LIMIT,
    HEADER,
    INLINE_LIMIT,
    LAYOUT_CDR,
    LAYOUT_SPLIT,
    LOAN_RESERVE,
    LOSS_GRACE,
    MAPPED,
    SPLIT,
    SPLIT_ONE,
    ScratchViews,
    align,
    blob_table,
    leased_memory,
)
from ._service import Service

if TYPE_CHECKING:
    from ._domain import ShmDomain



class _SlotPlan:
    """Where the parts of a split message go in a slot: fixed by its array lengths, so cached.

    The slot holds the header, the table (``SPLIT`` then one ``BLOB`` per array), the small
    part (the CDR of the message with those arrays empty) at ``small_at`` with room until
    the first blob, and each array at a 64-byte aligned offset. The table is packed once:
    it names the small part's room rather than its size (CDR needs no end marker).
    """

    __slots__ = ("blobs", "room", "size", "small_at", "table")

    def __init__(self, arrays: list[tuple[int, tuple[str, ...], np.dtype[Any], int]], reserve: int) -> None:
        table_end = HEADER.size + SPLIT.size + BLOB.size * len(arrays)
        self.small_at = align(table_end, 8) + 4
        offset = align(self.small_at + reserve, 64)
        self.room = offset - self.small_at
        blobs = []
        table = [SPLIT.pack(self.room, len(arrays))]
        for index, path, dtype, length in arrays:
            blobs.append((path, dtype, length, offset))
            table.append(BLOB.pack(index, self.small_at, offset, length * dtype.itemsize))
            offset = align(offset + length * dtype.itemsize, 64)
        self.size = offset if arrays else self.small_at + self.room
        self.blobs = tuple(blobs)
        self.table = b"".join(table)


class _Loan:
    """A slot handed out with a message by ``loan``; stored on the message itself."""

    __slots__ = ("arrays", "memory", "plan", "sample", "writer")

    def __init__(self, sample: Any, memory: memoryview, plan: _SlotPlan,
                 arrays: list[tuple[tuple[str, ...], np.ndarray[Any, Any]]], writer: ShmWriter | None) -> None:
        self.sample = sample
        self.memory = memory
        self.plan = plan
        self.arrays = arrays
        self.writer = writer


def _placed(loan_slot: Callable[[int], tuple[Any, memoryview]], plan: _SlotPlan
            ) -> tuple[Any, memoryview, list[tuple[tuple[str, ...], np.ndarray[Any, Any]]]]:
    """A slot laid out by ``plan``, its table written, and views on its blobs."""
    sample, memory = loan_slot(plan.size)
    memory[HEADER.size:HEADER.size + len(plan.table)] = plan.table
    return sample, memory, [(path, np.frombuffer(memory, dtype, length, at)) for path, dtype, length, at in plan.blobs]


def has_loan(message: Any) -> bool:
    return getattr(message, "_hetros_loan", None) is not None


_EMPTY: dict[np.dtype[Any], np.ndarray[Any, Any]] = {}


def _empty(dtype: np.dtype[Any]) -> np.ndarray[Any, Any]:
    """A shared, read-only empty array: what a published loan's arrays become."""
    array = _EMPTY.get(dtype)
    if array is None:
        array = np.empty(0, dtype)
        array.flags.writeable = False
        _EMPTY[dtype] = array
    return array


class ShmWriter(Writer):
    """Publishes into one service: arrays go into the slot as blobs (one copy, or none when loaned)."""

    lends_slots = True

    def __init__(self, service: Service, codec: Codec, slot: int) -> None:
        self._service = service
        self._codec = codec
        self._slot = slot
        # variable-length arrays travel as blobs; fixed-size ones stay in the CDR part
        self._arrays = [(index, field) for index, field in enumerate(codec.arrays) if field.length is None] \
            if isinstance(codec, MessageCodec) else []
        self._loan_plans: dict[tuple[tuple[str, int], ...], _SlotPlan] = {}
        self._blank: Callable[[], Any] | None = None  # what a loan's message is copied from, made on the first loan
        self._cdr = codec if isinstance(codec, MessageCodec) else None
        self._loan_slot = service.loan_scratch
        self._send = service.send
        self._send_cdr = service.send_cdr
        self.sent_bytes = 0  # what this writer put into shared memory (hetros top's bandwidth)
        service.publisher()

    def counters(self) -> dict[str, int]:
        return {"stalls": self._service.stalls, "bytes": self.sent_bytes}

    def has_room(self) -> bool:
        return self._service.has_room()

    def write(self, message: Any) -> None:
        cdr = self._cdr
        if cdr is None:  # a service envelope: one contiguous sample
            size = HEADER.size + self._codec.size(message)
            sample, memory = self._loan_slot(size)
            self._codec.encode_into(message, memory[HEADER.size:size])
            self._send(sample, memory, LAYOUT_CDR, self._slot)
            self.sent_bytes += size
            return
        loan = getattr(message, "_hetros_loan", None)  # set by every decoder and __init__; guarded all the same
        if loan is not None and loan.writer is self:
            object.__setattr__(message, "_hetros_loan", None)
            self._send_loan(message, loan)
            return
        body_size = cdr.body_size(message)
        if self._arrays and body_size > INLINE_LIMIT:
            self._send_copy(message)
            return
        self._send_cdr(message, body_size, cdr.encode_body, self._slot)
        self.sent_bytes += body_size

    def _send_copy(self, message: Any) -> None:
        """Large arrays go as aligned blobs (no zeroing, no CDR walk over them)."""
        codec = self._codec
        assert isinstance(codec, MessageCodec)
        arrays = []
        for index, field in self._arrays:
            array = np.asarray(get_path(message, field.path))
            if array.size:
                arrays.append((index, field.path, field.dtype, int(array.size)))
        plan = _SlotPlan(arrays, codec.lean_size(message))
        sample, memory, views = _placed(self._service.loan, plan)
        for path, view in views:
            np.copyto(view, get_path(message, path), casting="unsafe")
        self._finish(message, _Loan(sample, memory, plan, views, None))

    def _plan_for(self, sizes: dict[str, int]) -> _SlotPlan:
        codec = self._codec
        if not isinstance(codec, MessageCodec):
            raise TransportError("only topic messages can be loaned")
        key = tuple(sizes.items())
        plan = self._loan_plans.get(key)
        if plan is None:
            plan = self._loan_plan(codec, sizes)
            if len(self._loan_plans) > 64:  # lengths that keep changing must not grow the cache forever
                self._loan_plans.clear()
            self._loan_plans[key] = plan
        return plan

    def slot_loan_maker(self, sizes: dict[str, int]) -> Callable[[], Any] | None:
        """Slot loans (the split layout) only above ``INLINE_LIMIT``: below it a loan is better
        made in process memory and sent inline, one copy of a few kilobytes costing less than
        the split layout's bookkeeping."""
        return self.loan_maker(sizes) if self._plan_for(sizes).size > INLINE_LIMIT else None

    def owns_loan(self, message: Any) -> bool:
        return has_loan(message)

    def loan(self, sizes: dict[str, int]) -> Any:
        """A message whose primitive arrays live in a shared-memory slot (zero-copy publish)."""
        return self.loan_maker(sizes)()

    def loan_maker(self, sizes: dict[str, int]) -> Callable[[], Any]:
        """What makes such loans of these array lengths, their slot plan resolved once
        (``Publisher.loan`` keeps it per lengths: a loan in a loop looks nothing up)."""
        plan = self._plan_for(sizes)
        assert isinstance(self._codec, MessageCodec)
        if self._blank is None:
            self._blank = default_maker(self._codec.cls)
        blank, service_loan = self._blank, self._service.loan

        def make() -> Any:
            sample, memory, views = _placed(service_loan, plan)
            message = blank()
            for path, view in views:
                set_path(message, path, view)
            object.__setattr__(message, "_hetros_loan", _Loan(sample, memory, plan, views, self))
            return message
        return make

    def _loan_plan(self, codec: MessageCodec, sizes: dict[str, int]) -> _SlotPlan:
        wanted = dict(sizes)
        arrays: list[tuple[int, tuple[str, ...], np.dtype[Any], int]] = []
        for index, field in self._arrays:
            length = wanted.pop(".".join(field.path), 0)
            if length:
                arrays.append((index, field.path, field.dtype, length))
        if wanted:
            known = ", ".join(".".join(f.path) for _i, f in self._arrays) or "none"
            raise TransportError(
                f"{codec.typename} has no variable-length primitive array {', '.join(wanted)!s}; "
                f"loan sizes can be given for: {known}"
            )
        return _SlotPlan(arrays, LOAN_RESERVE)

    def _send_loan(self, message: Any, loan: _Loan) -> None:
        for path, array in loan.arrays:
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
        for path, array in loan.arrays:
            set_path(message, path, _empty(array.dtype))

    def _finish(self, message: Any, loan: _Loan) -> None:
        """Encode the small part into its room and send the slot."""
        codec = self._codec
        assert isinstance(codec, MessageCodec)
        at, room = loan.plan.small_at, loan.plan.room
        try:
            codec.encode_lean_at(message, loan.memory, at, at + room)
        except (struct.error, ValueError, IndexError):
            small = codec.lean_size(message)
            if small <= room:
                raise
            raise TransportError(
                f"{codec.typename}: {small} bytes besides its arrays exceed the {room}-byte room "
                "a loaned shared-memory slot keeps for them; shorten its strings or lists"
            ) from None
        self._service.send(loan.sample, loan.memory, LAYOUT_SPLIT, self._slot)
        self.sent_bytes += loan.plan.size

    def assert_liveliness(self) -> None:
        self._service.publisher()  # a publisher that never sent is known (its pid) from now on
        self._service.credits.asserted_ns = time.monotonic_ns()

    def close(self) -> None:
        return None


class _Port:
    """One publishing target's service as seen by one reader."""

    __slots__ = ("expected", "jump", "service", "subscriber", "suspect_since")

    def __init__(self, service: Service, subscriber: Any, start: int) -> None:
        self.service = service
        self.subscriber = subscriber
        self.expected = start + 1
        self.suspect_since = 0.0
        # (expected, the number seen) while a forward jump of a reliable topic's numbers is unproven
        self.jump: tuple[int, int] | None = None


bind_slots(_Port, ("subscriber", "service", "expected", "suspect_since"))


class ShmReader(Reader):
    """Takes from every publishing target's service of one topic.

    Delivered primitive arrays are read-only views on the shared-memory slot; the slot
    is returned when the last of them is gone (``msg.copy()`` keeps data longer).
    """

    def __init__(self, domain: ShmDomain, services: list[Service], codec: Codec, slot: int, wake: Wake,
                 channel: WakeChannel) -> None:
        self._domain = domain
        self._codec = codec
        self._slot = slot
        self._closed = False
        self._channel = channel
        self.dropped = 0  # damaged samples dropped (a same-user process wrote into the segment)
        self._wake = wake
        self._ports: list[_Port] = []
        self.event = channel.register(wake, self.pending)
        self._next = 0
        self._lock = threading.Lock()
        self._borrowed: list[None] = []
        self._cdr = codec if isinstance(codec, MessageCodec) else None
        # a decoded message of a type without primitive arrays keeps nothing of the sample,
        # so the sample is read through a reused view and returned at once
        self._copies = self._cdr is not None and self._cdr.decode_copies
        self._decode_body = self._cdr.decode_body if self._cdr is not None else None
        self._scratch = ScratchViews(readonly=True)
        self.topic = services[0].topic if services else ""
        for service in services:
            subscriber, start = service.subscriber(slot, channel, self.event)
            self._ports.append(_Port(service, subscriber, start))
        self._only_port = self._ports[0] if len(self._ports) == 1 else None
        # a lifespan is checked by the reference path (the compiled take does not read the send time)
        lifespan = services[0].qos.lifespan if services else None
        self._lifespan_ns = None if lifespan is None else int(lifespan * 1e9)
        self.expired = 0  # messages dropped unread for being older than the lifespan
        self.overwritten = 0  # keep_last: messages replaced by newer ones before this reader took them
        self._compiled = take_cdr is not None and self._decode_body is not None and self._lifespan_ns is None
        # how one publishing target's next message is taken: the compiled common case where it applies
        self._take_from: Callable[[_Port], Any | None] = (
            self._take_compiled if self._compiled else self._take_reference)
        wake()

    # -- taking ----------------------------------------------------------------------------

    def counters(self) -> dict[str, int]:
        return {"dropped": self.overwritten}

    def pending(self) -> bool:
        for port in self._ports:  # a loop, not any(generator): this runs on every poll of a hot node
            if port.subscriber.has_samples():
                return True
        return False

    def try_take(self) -> Any | None:
        lock = self._lock
        lock.acquire()  # not ``with``: this runs on every poll of a hot node, and ``with`` costs 0.08 µs more
        try:
            ports = self._ports
            if len(ports) == 1:  # one publishing target, the common case: no rotation
                return self._take_from(ports[0])
            for _ in range(len(ports)):
                port = ports[self._next]
                self._next = (self._next + 1) % len(ports)
                message = self._take_from(port)
                if message is not None:
                    return message
            return None
        finally:
            lock.release()

    def taker(self) -> Callable[[], Any | None]:
        """One publishing target and the compiled path, the common case: one call per message."""
        return self._try_take_only_port if self._compiled and self._only_port is not None else self.try_take

    def _try_take_only_port(self) -> Any | None:
        """``try_take`` with one port and the compiled path: ``_take_compiled`` inlined."""
        lock = self._lock
        lock.acquire()
        try:
            port = self._only_port
            if port is None:  # closed
                return None
            while True:
                try:
                    got = take_cdr(port, self._slot, self._copies, self._borrowed,  # type: ignore[misc]
                                   self._decode_body)
                except iox2.ReceiveError as exc:
                    raise self._receive_failed(port, exc) from exc
                except SerializationError as exc:  # accounted for, then its body did not decode
                    self._count_damaged(port, str(exc))
                    continue
                if got is None:
                    return None
                if got is False or type(got) is tuple:
                    return self._finish_compiled(port, got)
                return got
        finally:
            lock.release()

    def _take_reference(self, port: _Port) -> Any | None:
        """The next message of one publishing target (``self._lock`` held), None when it has none."""
        try:
            sample = port.subscriber.receive()
        except iox2.ReceiveError as exc:
            raise self._receive_failed(port, exc) from exc
        if sample is None:
            if port.service.blocking:
                self._check_arrival(port)
            return None
        size = sample.header.number_of_elements
        if not MAPPED.holds(sample.payload_ptr, size):
            del sample
            return self._skip_damaged(port, f"its size ({size} bytes) runs past the shared-memory segment it is in")
        if self._copies:
            # the message will hold no view on the sample: it goes back once decoded
            memory = self._scratch.at(sample.payload_ptr, size)[:size]
        else:
            memory = leased_memory(sample.payload_ptr, size, sample, self._borrowed)
            del sample
        return self._took(port, memory, size)

    def _take_compiled(self, port: _Port) -> Any | None:
        """``_take_reference`` with its common case compiled (``_hotpath``); the rest goes to ``_took``."""
        assert take_cdr is not None
        try:
            got = take_cdr(port, self._slot, self._copies, self._borrowed, self._decode_body)
        except iox2.ReceiveError as exc:
            raise self._receive_failed(port, exc) from exc
        except SerializationError as exc:  # accounted for, then its body did not decode
            self._count_damaged(port, str(exc))
            return self._take_compiled(port)
        if got is None:
            return None
        if got is False or type(got) is tuple:
            return self._finish_compiled(port, got)
        return got

    def _finish_compiled(self, port: _Port,
                         got: Literal[False] | tuple[memoryview | None, int] | tuple[memoryview, int, int]
                         ) -> Any | None:
        """What ``take_cdr`` leaves to the reference path: a publisher to check, a sample to
        finish, one accounted for (a split-layout sample) to decode, or (None, size) for a
        sample whose size runs past its segment (released unread)."""
        if got is False:
            self._check_arrival(port)
            return None
        if got[0] is None:  # the compiled path found the sample's size past its segment
            return self._skip_damaged(port, f"its size ({got[1]} bytes) runs past the shared-memory segment it is in")
        if len(got) == 3:
            try:
                return self._decode(got[0], got[2])
            except SerializationError as exc:
                self._count_damaged(port, str(exc))
                return self._take_from(port)
        return self._took(port, got[0], got[1])

    def _receive_failed(self, port: _Port, exc: Exception) -> TransportError:
        return TransportError(f"cannot receive on {port.service.topic} from target {port.service.target!r}: "
                              f"{exc}; {fd_hint()}")

    def _took(self, port: _Port, memory: memoryview, size: int) -> Any:
        """A received sample's bytes to a message, its sequence number and the credits accounted."""
        service = port.service
        if size < HEADER.size:
            return self._skip_damaged(port, f"a {size}-byte sample is shorter than hetros' {HEADER.size}-byte "
                                            "header")
        seq, _publisher_slot, layout, sent_ns = HEADER.unpack_from(memory, 0)
        if port.jump is not None:
            self._settle_jump(port, seq)
        if seq > port.expected:
            # sends are serialised and the credits say "published" right after each: a sequence
            # number beyond published+1 was not written by the publisher
            published = service.credits.published
            if seq > published + 1:
                return self._skip_damaged(port, f"sequence number {seq} at offset 0 is beyond the "
                                                f"{published} published")
            if service.blocking:
                # a gap, or one damaged number: the next sample tells (``_settle_jump``); until then
                # this one counts as the one expected, and no credit is given for what it skipped
                port.jump = (port.expected, seq)
                seq = port.expected
            else:
                self.overwritten += seq - port.expected  # keep_last: the publisher's newer ones replaced them
        # one sent before this reader joined may come after the join's mark: never count backwards
        seq = max(seq, port.expected - 1)
        port.expected = seq + 1
        if port.jump is not None:
            # suspect until settled: every take and every empty poll comes to this path, not the compiled one
            if not port.suspect_since:
                port.suspect_since = time.monotonic()
                self._channel.suspect(self.event, True)
        elif port.suspect_since:
            port.suspect_since = 0.0
            self._channel.suspect(self.event, False)
        credits = service.credits
        # a blocked publisher is woken once its FIFO here is half empty, not per take:
        # it then sends half a FIFO without waiting (one wake-up per depth/2 messages)
        if credits.set_taken(self._slot, seq) and service.blocking and \
                credits.published - seq <= service.qos.depth // 2:
            self._domain.notify_back(service.target, credits.back_event)
        if self._lifespan_ns is not None and time.monotonic_ns() - sent_ns > self._lifespan_ns:
            self.expired += 1  # older than the topic's lifespan: taken (its credit given back), not delivered
            return self._take_from(port)
        if len(self._borrowed) >= BORROW_LIMIT - 2:
            memory = memoryview(bytes(memory))
        try:
            if layout == LAYOUT_CDR and self._decode_body is not None and size >= HEADER.size + 4 and \
                    memory[HEADER.size + 1] == 1:  # little-endian CDR: straight to the type's decoder
                return self._decode_body(memory, HEADER.size + 4, size)
            return self._decode(memory, layout)
        except SerializationError as exc:
            self._count_damaged(port, str(exc))
            return self._take_from(port)

    def _account(self, port: _Port, seq: int) -> None:
        """Record ``seq`` as taken, and wake the publisher if it waits for room here."""
        service = port.service
        if service.credits.set_taken(self._slot, seq) and service.blocking:
            self._domain.notify_back(service.target, service.credits.back_event)

    def _count_damaged(self, port: _Port, why: str) -> None:
        self.dropped += 1
        log.error("topic %s: dropped a damaged sample from target %r (%d so far): %s", port.service.topic,
                  port.service.target, self.dropped, why)

    def _skip_damaged(self, port: _Port, why: str) -> Any | None:
        """Drop a sample whose header is damaged as if it were the one expected (its credit is
        given back, so neither the publisher nor the next takes wait for it) and take the next."""
        self._count_damaged(port, why)
        self._account(port, port.expected)
        port.expected += 1
        return self._take_from(port)

    def _settle_jump(self, port: _Port, seq: int | None) -> None:
        """Decide an unproven jump by what follows it (``seq``, the next number; None when everything
        the publisher counts as sent was taken): the publisher's numbering going on from the jump
        proves messages lost; anything else shows the jump was one damaged number."""
        before, jumped = port.jump or (0, 0)
        port.jump = None
        if seq == jumped + 1:
            port.expected = seq
            self._account(port, jumped)
            self._lost(port, jumped - before, before)
        after = "every message the publisher counts as sent was taken" if seq is None else f"#{seq} came next"
        self._count_damaged(port, f"its sequence number {jumped} was not the publisher's (#{before} was due, and "
                                  f"{after}); it was delivered as #{before}")

    def _check_arrival(self, port: _Port) -> None:
        """Nothing to receive: is that true, or did iceoryx2 fail to connect to the publisher?"""
        credits = port.service.credits
        if not credits.holds(self._slot, self._channel.key, self.event):
            log.error("topic %s: this subscriber's slot %d in the credits of target %r was overwritten (another "
                      "process of this user wrote into /dev/shm); written again", port.service.topic, self._slot,
                      port.service.target)
            credits.rejoin(self._slot, self._channel.key, self.event)
        published = credits.published
        if port.jump is not None and published < port.expected:
            self._settle_jump(port, None)
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
            missed, first = published - port.expected + 1, port.expected
            port.expected = published + 1  # reported once: a restarted node goes on from here
            port.jump = None
            port.suspect_since = 0.0
            self._channel.suspect(self.event, False)
            self._account(port, published)
            self._lost(port, missed, first)

    def _lost(self, port: _Port, count: int, first: int) -> None:
        service = port.service
        publisher = service.credits.publisher_pid
        if publisher and not pid_alive(publisher):
            cause = (f"the publishing process (pid {publisher}) ended before this subscriber took them (a "
                     "process whose nodes returned waits for its subscribers while they keep taking, and "
                     f"gives up after {service.qos.publish_timeout:g} s without progress; a killed one "
                     "cannot wait)")
        else:
            cause = ("iceoryx2 could not deliver them, most often because a process ran out of file "
                     f"descriptors ({fd_hint()})")
        raise TransportError(
            f"reliable topic {service.topic}: {count} message(s) from target {service.target!r} "
            f"(from #{first}) never reached this subscriber although the publisher sent them; {cause}"
        )

    def _decode(self, memory: memoryview, layout: int) -> Any:
        cdr = self._cdr
        if layout == LAYOUT_CDR:
            if cdr is not None:
                return cdr.decode_at(memory, HEADER.size, len(memory))
            return self._codec.decode(memory[HEADER.size:])
        end = len(memory)
        if layout == LAYOUT_SPLIT and cdr is not None and end >= HEADER.size + SPLIT_ONE.size:
            # one array, every check of the general path passed: decoded here in one unpack
            room, count, index, small_at, offset, nbytes = SPLIT_ONE.unpack_from(memory, HEADER.size)
            arrays = cdr.arrays
            if count == 1 and index < len(arrays) and small_at % 8 == 4 and small_at + room <= end \
                    and offset + nbytes <= end:
                message = cdr.decode_at(memory, small_at, small_at + room)
                field = arrays[index]
                dtype = field.dtype
                set_path(message, field.path, np.frombuffer(memory, dtype, nbytes // dtype.itemsize, offset))
                return message
        return self._decode_split(memory, layout)

    def _decode_split(self, memory: memoryview, layout: int) -> Any:
        """The split layout's general case, and every refusal of a damaged sample."""
        if layout != LAYOUT_SPLIT or not isinstance(self._codec, MessageCodec):
            raise SerializationError(f"unknown shared-memory layout {layout} at offset 12 of the sample header")
        arrays = self._codec.arrays
        if len(memory) < HEADER.size + SPLIT.size:
            raise SerializationError(f"a {len(memory)}-byte sample of {self._codec.typename} is too short "
                                     "for the split layout's table")
        room, count = SPLIT.unpack_from(memory, HEADER.size)
        if count > len(arrays) or HEADER.size + SPLIT.size + BLOB.size * count > len(memory):
            raise SerializationError(f"the table at offset {HEADER.size} names {count} arrays; "
                                     f"{self._codec.typename} has {len(arrays)} (the sample is damaged)")
        table = blob_table(count).unpack_from(memory, HEADER.size + SPLIT.size)
        small_at = table[1] if count else align(HEADER.size + SPLIT.size, 8) + 4
        if small_at % 8 != 4 or small_at + room > len(memory):
            raise SerializationError(
                f"the small part at offset {small_at} ({room} bytes) does not fit a {len(memory)}-byte "
                f"sample of {self._codec.typename} (the table at offset {HEADER.size} is damaged)"
            )
        message = self._codec.decode_at(memory, small_at, small_at + room)
        end = len(memory)
        for position in range(0, 4 * count, 4):
            index, _small_at, offset, nbytes = table[position:position + 4]
            if index >= len(arrays) or offset + nbytes > end:
                raise SerializationError(
                    f"blob {index} at offset {offset} ({nbytes} bytes) does not fit a "
                    f"{end}-byte sample of {self._codec.typename}"
                )
            field = arrays[index]
            dtype = field.dtype
            set_path(message, field.path, np.frombuffer(memory, dtype, nbytes // dtype.itemsize, offset))
        return message

    def liveliness(self) -> tuple[int, int]:
        """A publishing process is alive while it runs (``automatic``) and, for
        ``manual_by_topic``, while it asserted within ``lease_duration``; one that never
        published is not counted."""
        alive = gone = 0
        now = time.monotonic_ns()
        for port in self._ports:
            credits, qos = port.service.credits, port.service.qos
            pid = credits.publisher_pid
            if not pid:
                continue
            ok = pid_alive(pid)
            if ok and qos.liveliness == "manual_by_topic" and qos.lease_duration is not None:
                ok = now - credits.asserted_ns <= qos.lease_duration * 1e9
            elif ok and qos.lease_duration is None and qos.liveliness == "manual_by_topic":
                ok = credits.asserted_ns != 0
            alive, gone = alive + ok, gone + (not ok)
        return alive, gone

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._channel.unregister(self.event, self._wake)
        for port in self._ports:
            port.service.credits.leave(self._slot)
        self._ports.clear()
        self._only_port = None


