"""What a node's endpoint holds: one writer over every transport of its edges, one reader
draining them, and the ownership rule applied once, above every transport.

The ownership rule: a published message is handed over (it becomes read-only); arrays the
caller still owns are copied when another reader in this process would see them, and a
message whose arrays live in a transport's memory (a loan) leaves with that transport's send.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from .._errors import TransportError
from ..msg import (
    LoanBuffer,
    Message,
    TypeRegistry,
    array_fields,
    default_maker,
    freeze,
    hand_over,
    loaned_array,
    set_path,
)
from ..msg import copy as copy_message
from ..transport import Reader, Wake, Writer, carried_message


def merge_counters(counters: Iterable[dict[str, int]]) -> dict[str, int]:
    """Counters of several parts (or endpoints) of one topic, added up by name."""
    total: dict[str, int] = {}
    for each in counters:
        for name, value in each.items():
            total[name] = total.get(name, 0) + value
    return total


def _hand_over(item: Any, copy_arrays: bool) -> Any:
    """Freeze a message (or a service envelope's message) on its way out; see ``msg.hand_over``."""
    message = carried_message(item)
    if message is not None:
        hand_over(message, copy_arrays)
    return item


class EndpointWriter(Writer):
    """The writer a node's publisher (or service end) holds: what it writes is handed over here,
    then fed to the transports of its edges."""

    def __init__(self, parts: list[Writer], types: TypeRegistry) -> None:
        self._parts = parts
        self._types = types
        self._lender = next((p for p in parts if p.lends_slots), None)
        self._local = any(p is not self._lender for p in parts)

    def loan_maker(self, cls: type[Message], sizes: dict[str, int]) -> Callable[[], Message]:
        """What makes loans of these array lengths (``Publisher.loan`` keeps it): messages to
        fill in place, their arrays in a shared-memory slot when a process reads them and
        they are large, otherwise in memory hetros owns (sent inline)."""
        sizes = {name.replace("__", "."): length for name, length in sizes.items()}
        lender = self._lender
        slot_maker = None if lender is None else lender.slot_loan_maker(sizes)
        if slot_maker is not None:
            return slot_maker
        arrays = self._arrays_of(cls, sizes)
        blank = default_maker(cls)
        if len(arrays) == 1 and len(arrays[0][0]) == 1:  # one top-level array, the common loan
            (name,), dtype, length = arrays[0]
            shape, nbytes = (length,), length * dtype.itemsize

            def one_array() -> Message:  # loaned_array inlined: a third of a small loan's cost
                message: Message = blank()
                setattr(message, name, np.ndarray(shape, dtype, LoanBuffer(nbytes)))
                return message
            return one_array

        def each_array() -> Message:
            message: Message = blank()
            for path, dtype, length in arrays:
                set_path(message, path, loaned_array(length, dtype))
            return message
        return each_array

    def _arrays_of(self, cls: type[Message], sizes: dict[str, int]) -> list[tuple[tuple[str, ...], Any, int]]:
        wanted = dict(sizes)
        arrays = []
        for field in array_fields(self._types, cls.__msgtype__):
            length = wanted.pop(".".join(field.path), None)
            if length is not None and field.length is None:
                arrays.append((field.path, field.dtype, length))
        if wanted:
            raise TransportError(f"{cls.__msgtype__} has no variable-length primitive array "
                                 f"{', '.join(wanted)}")
        return arrays

    def sends_in_place(self, message: Any) -> bool:
        """Whether writing this loaned message hands its shared-memory slot over as it is, with no copy."""
        lender = self._lender
        return lender is not None and lender.owns_loan(message) and all(p is lender for p in self._parts)

    def write(self, message: Any) -> None:
        lender = self._lender
        if lender is not None and lender.owns_loan(message):
            others = [part for part in self._parts if part is not lender]
            if others:
                # the slot leaves with the shared-memory send: in-process readers get their own copy
                local = freeze(copy_message(message))
                for part in others:
                    part.write(local)
            lender.write(_hand_over(message, copy_arrays=False))
            return
        _hand_over(message, copy_arrays=self._local)
        for part in self._parts:
            part.write(message)

    def counters(self) -> dict[str, int]:
        return merge_counters(part.counters() for part in self._parts)

    def has_room(self) -> bool:
        return all(part.has_room() for part in self._parts)

    def assert_liveliness(self) -> None:
        for part in self._parts:
            part.assert_liveliness()

    def close(self) -> None:
        for part in self._parts:
            part.close()


class _OneTransportWriter(EndpointWriter):
    """The common case, one transport: a loan needs no copy for other parts, and a topic's
    message is sealed without looking for a service envelope."""

    def __init__(self, parts: list[Writer], types: TypeRegistry) -> None:
        super().__init__(parts, types)
        self._write_part = parts[0].write

    def write(self, message: Any) -> None:
        if isinstance(message, Message):
            hand_over(message, self._local)
        else:
            _hand_over(message, self._local)
        self._write_part(message)


def endpoint_writer(parts: list[Writer], types: TypeRegistry) -> EndpointWriter:
    return _OneTransportWriter(parts, types) if len(parts) == 1 else EndpointWriter(parts, types)


class MergedReader(Reader):
    """An endpoint fed by several transports (subscribers in this process and in others)."""

    def __init__(self, parts: list[Reader]) -> None:
        self._parts = parts

    def try_take(self) -> Any | None:
        for part in self._parts:
            item = part.try_take()
            if item is not None:
                return item
        return None

    def pending(self) -> bool:
        return any(part.pending() for part in self._parts)

    def liveliness(self) -> tuple[int, int] | None:
        counts = [c for c in (part.liveliness() for part in self._parts) if c is not None]
        return (sum(c[0] for c in counts), sum(c[1] for c in counts)) if counts else None

    def counters(self) -> dict[str, int]:
        return merge_counters(part.counters() for part in self._parts)

    def close(self) -> None:
        for part in self._parts:
            part.close()


class Relay:
    """A wake-up target fixed later: readers opened at start-up, before their node runs."""

    def __init__(self) -> None:
        self.target: Wake | None = None

    def __call__(self) -> None:
        target = self.target
        if target is not None:
            target()


class RetainedReader(Reader):
    """A reader opened from the plan at start-up; it outlives the node that uses it.

    When its node fails and restarts, the FIFO (and its place in the publisher's credits)
    stays, so the restarted node resumes where the failed one stopped.
    """

    def __init__(self, inner: Reader, relay: Relay, release: Callable[[RetainedReader], None]) -> None:
        self.inner = inner
        self.relay = relay
        self._release = release

    def try_take(self) -> Any | None:
        return self.inner.try_take()

    def taker(self) -> Callable[[], Any | None]:
        return self.inner.taker()

    def pending(self) -> bool:
        return self.inner.pending()

    def liveliness(self) -> tuple[int, int] | None:
        return self.inner.liveliness()

    def counters(self) -> dict[str, int]:
        return self.inner.counters()

    def close(self) -> None:
        self.relay.target = None
        self._release(self)
