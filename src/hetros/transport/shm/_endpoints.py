"""Writers and readers of one shared-memory topic."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..._errors import SerializationError, TransportError
from ...msg import get_path, set_path
from .._base import Codec, Reader, Wake, Writer
from .._codec import MessageCodec
from ._events import (
    WakeChannel,
    fd_hint,
)
from ._iceoryx import iox2
from ._sample import (
    BLOB,
    BORROW_LIMIT,
    HEADER,
    INLINE_LIMIT,
    LAYOUT_CDR,
    LAYOUT_SPLIT,
    LOAN_RESERVE,
    LOSS_GRACE,
    SPLIT,
    align,
    slot_memory,
)
from ._service import Service

if TYPE_CHECKING:
    from ._domain import ShmDomain



@dataclass
class _Loan:
    """A slot handed out with a message by ``loan``; stored on the message itself."""

    sample: Any
    memory: memoryview
    arrays: list[tuple[int, tuple[str, ...], np.ndarray[Any, Any], int]]
    small_at: int
    writer: ShmWriter | None = None


def take_loan(message: Any, writer: ShmWriter | None = None) -> _Loan | None:
    """Detach the loan of ``message`` (of ``writer``, when given); None when it has none."""
    loan: _Loan | None = getattr(message, "_hetros_loan", None)
    if loan is None or (writer is not None and loan.writer is not writer):
        return None
    object.__setattr__(message, "_hetros_loan", None)
    return loan


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

    def __init__(self, service: Service, codec: Codec, slot: int) -> None:
        self._service = service
        self._codec = codec
        self._slot = slot
        # variable-length arrays travel as blobs; fixed-size ones stay in the CDR part
        self._arrays = [(index, field) for index, field in enumerate(codec.arrays) if field.length is None] \
            if isinstance(codec, MessageCodec) else []
        service.publisher()

    def write(self, message: Any) -> None:
        loan = take_loan(message, self)
        if loan is not None:
            self._send_loan(message, loan)
            return
        size = HEADER.size + self._codec.size(message)
        if self._arrays and size > INLINE_LIMIT:
            # large arrays go as aligned blobs: only the small part needs zeroing
            self._send_copy(message)
            return
        sample, memory = self._service.loan(size)
        self._codec.encode_into(message, memory[HEADER.size:])
        self._service.send(sample, memory, LAYOUT_CDR, self._slot)

    def _place(self, plan: list[tuple[int, tuple[str, ...], np.dtype[Any], int]], reserve: int
               ) -> tuple[Any, memoryview, int, list[tuple[int, tuple[str, ...], np.ndarray[Any, Any], int]]]:
        """A slot with room for the small part and 64-byte aligned blobs; views on the blobs."""
        table_end = HEADER.size + SPLIT.size + BLOB.size * len(plan)
        small_at = align(table_end, 8) + 4
        offset = align(small_at + reserve, 64)
        offsets = []
        for _index, _path, dtype, length in plan:
            offsets.append(offset)
            offset = align(offset + length * dtype.itemsize, 64)
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
        assert isinstance(self._codec, MessageCodec)
        sample, memory, small_at, views = self._place(plan, self._codec.lean_size(message))
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
        object.__setattr__(message, "_hetros_loan", _Loan(sample, memory, views, small_at, self))
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
            set_path(message, path, _empty(array.dtype))

    def _finish(self, message: Any, loan: _Loan) -> None:
        """Encode the small part, write the blob table and send the slot."""
        codec = self._codec
        assert isinstance(codec, MessageCodec)
        memory = loan.memory
        small = codec.lean_size(message)
        if loan.small_at + small > len(memory) or (loan.arrays and loan.small_at + small > loan.arrays[0][3]):
            raise TransportError(
                f"{codec.typename}: {small} bytes besides its arrays exceed the "
                f"{LOAN_RESERVE}-byte reserve of a shared-memory slot; shorten its strings"
            )
        codec.encode_lean_into(message, memory[loan.small_at:loan.small_at + small])
        SPLIT.pack_into(memory, HEADER.size, small, len(loan.arrays))
        for position, (index, _path, array, at) in enumerate(loan.arrays):
            BLOB.pack_into(memory, HEADER.size + SPLIT.size + BLOB.size * position, index, loan.small_at,
                           at, array.nbytes)
        self._service.send(loan.sample, memory, LAYOUT_SPLIT, self._slot)

    def close(self) -> None:
        return None


class _Lease:
    """Holds a received sample; it goes back to the publisher when no message refers to it.

    ``borrowed`` has one entry per live lease (list append and pop are atomic, and a lease
    may die in any thread).
    """

    __slots__ = ("borrowed", "sample")

    def __init__(self, sample: Any, borrowed: list[None]) -> None:
        self.sample = sample
        self.borrowed = borrowed
        borrowed.append(None)

    def __del__(self) -> None:
        self.borrowed.pop()


class _Port:
    """One publishing target's service as seen by one reader."""

    __slots__ = ("expected", "service", "subscriber", "suspect_since")

    def __init__(self, service: Service, subscriber: Any, start: int) -> None:
        self.service = service
        self.subscriber = subscriber
        self.expected = start + 1
        self.suspect_since = 0.0


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
        self._wake = wake
        self.event = channel.register(wake)
        self._ports: list[_Port] = []
        self._next = 0
        self._lock = threading.Lock()
        self._borrowed: list[None] = []
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
                try:
                    sample = port.subscriber.receive()
                except iox2.ReceiveError as exc:
                    raise TransportError(f"cannot receive on {service.topic} from target {service.target!r}: "
                                         f"{exc}; {fd_hint()}") from exc
                if sample is None:
                    if service.blocking:
                        self._check_arrival(port)
                    continue
                size = sample.header.number_of_elements
                memory = slot_memory(sample.payload_ptr, size, _Lease(sample, self._borrowed))
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
                if len(self._borrowed) >= BORROW_LIMIT - 2:
                    memory = memoryview(bytes(memory))
                return self._decode(memory.toreadonly(), layout)
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
            f"({fd_hint()})"
        )

    def _decode(self, memory: memoryview, layout: int) -> Any:
        if layout == LAYOUT_CDR:
            return self._codec.decode(memory[HEADER.size:])
        if layout != LAYOUT_SPLIT or not isinstance(self._codec, MessageCodec):
            raise SerializationError(f"unknown shared-memory layout {layout} at offset 12 of the sample header")
        small, count = SPLIT.unpack_from(memory, HEADER.size)
        arrays = self._codec.arrays
        blobs = [BLOB.unpack_from(memory, HEADER.size + SPLIT.size + BLOB.size * i) for i in range(count)]
        small_at = blobs[0][1] if blobs else align(HEADER.size + SPLIT.size, 8) + 4
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


