"""What a node's endpoint holds: one writer over every transport of its edges, one reader
draining them, and the ownership rule applied once, above every transport.

The ownership rule: a published message is handed over (it becomes read-only); arrays the
caller still owns are copied when another reader in this process would see them, and a
message whose arrays live in a transport's memory (a loan) leaves with that transport's send.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from .._errors import TransportError
from .._qos import QoS
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
        self.shares_objects = any(p.shares_objects for p in parts)

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

    def write_kept(self, message: Any) -> None:
        """Write a message its caller keeps and may change afterwards, neither sealed nor copied: only
        for a writer whose parts all serialize it (``shares_objects`` False) and a message no transport
        lent."""
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
        self._lock = threading.Lock()
        # unclaimed while the node spins (lapse): what it took meanwhile, each with when it was taken
        self._lapsed: deque[tuple[float, Any]] | None = None
        self._backlog: deque[Any] = deque()  # what a late joiner keeps of what came before it (join_late)

    def lapse(self, depth: int) -> None:
        """Its node spins and no subscription claimed this reader: from now on it is not start-up order
        that keeps the subscription away, and a subscription that does not exist yet makes no publisher
        wait (as in ROS 2). It drains itself as messages come, keeping the newest ``depth``."""
        with self._lock:
            if self._lapsed is None:
                self._lapsed = deque(maxlen=depth)
                self.relay.target = self._drain
        self._drain()

    def _drain(self) -> None:
        with self._lock:
            if self._lapsed is not None:
                self._take_all(self._lapsed)

    def _take_all(self, into: deque[tuple[float, Any]]) -> None:
        """Everything the reader holds now, each with when it was taken (the lifespan's clock)."""
        while (message := self.inner.try_take()) is not None:
            into.append((time.monotonic(), message))

    def join_late(self, qos: QoS) -> None:
        """A subscription made after its node began to spin joins as ROS 2's late joiner would: of what
        came before it, a volatile one keeps nothing and a transient_local one the newest ``depth``
        that its lifespan has not expired."""
        with self._lock:
            lapsed, self._lapsed = self._lapsed or deque(), None
            self._take_all(lapsed)
        oldest = -math.inf if qos.lifespan is None else time.monotonic() - qos.lifespan
        kept = [message for taken, message in lapsed if taken >= oldest] if qos.keeps_history else []
        self._backlog = deque(kept[-qos.depth:])

    def try_take(self) -> Any | None:
        if self._backlog:
            return self._backlog.popleft()
        return self.inner.try_take()

    def taker(self) -> Callable[[], Any | None]:
        fast = self.inner.taker()
        backlog = self._backlog
        if not backlog:
            return fast

        def take() -> Any | None:
            return backlog.popleft() if backlog else fast()
        return take

    def pending(self) -> bool:
        return bool(self._backlog) or self.inner.pending()

    def liveliness(self) -> tuple[int, int] | None:
        return self.inner.liveliness()

    def counters(self) -> dict[str, int]:
        return self.inner.counters()

    def close(self) -> None:
        self.relay.target = None
        self._release(self)


class TopicReaders:
    """One node's transport reader of a topic, shared by every subscription the node makes to it.

    ROS delivers each message to each subscription, and two subscriptions of one node to one topic are
    common (rospy_tutorials' "with userdata", a callback and a ``take`` loop side by side). The plan
    has one endpoint per node and topic, so the node opens the topic once; a second subscription turns
    the reader into branches, one FIFO per subscription, each with its subscription's depth. A reliable
    keep_all branch that is full stops the reader from taking more, so the FIFO behind it fills and
    the publisher waits, as for a slow subscriber; a keep_last branch drops its oldest.
    """

    def __init__(self, inner: Reader, relay: Relay, forget: Callable[[], None]) -> None:
        self.inner = inner
        self.relay = relay
        self._forget = forget
        self._lock = threading.Lock()
        self._branches: list[_Branch] = []
        self.closed = False

    def sole(self) -> Reader:
        """The reader of the first subscription (the relay wakes it): the transport's own, until a second
        one comes."""
        return _Sole(self)

    def branch(self, wake: Wake, qos: QoS) -> Reader:
        """One subscription's own FIFO of the topic (the first subscription's too, once there are two)."""
        branch = _Branch(self, wake, qos)
        with self._lock:
            self._branches.append(branch)
        self.relay.target = self._wake_all
        wake()  # what the transport already holds is this branch's too
        return branch

    def _wake_all(self) -> None:
        for branch in list(self._branches):
            branch.wake()

    def fill(self, taker: _Branch) -> None:
        """Move what the transport holds into every branch, while each that must not lose has room."""
        woken: list[_Branch] = []
        with self._lock:
            branches = self._branches
            while not any(b.blocking and len(b.items) >= b.depth for b in branches):
                item = self.inner.try_take()
                if item is None:
                    break
                for branch in branches:
                    if len(branch.items) >= branch.depth:
                        branch.items.popleft()
                        branch.dropped += 1
                    branch.items.append(item)
                    if branch is not taker and branch not in woken:
                        woken.append(branch)
        for branch in woken:
            branch.wake()

    def remove(self, branch: _Branch) -> None:
        with self._lock:
            if branch in self._branches:
                self._branches.remove(branch)
            last = not self._branches
        if last:
            self.close()

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self._forget()
            self.inner.close()


class _Sole(Reader):
    """A node's only subscription to a topic: the transport's reader as it is (its fast take included)."""

    def __init__(self, shared: TopicReaders) -> None:
        self.shared = shared

    def try_take(self) -> Any | None:
        return self.shared.inner.try_take()

    def taker(self) -> Callable[[], Any | None]:
        return self.shared.inner.taker()

    def pending(self) -> bool:
        return self.shared.inner.pending()

    def liveliness(self) -> tuple[int, int] | None:
        return self.shared.inner.liveliness()

    def counters(self) -> dict[str, int]:
        return self.shared.inner.counters()

    def close(self) -> None:
        self.shared.close()


class _Branch(Reader):
    def __init__(self, shared: TopicReaders, wake: Wake, qos: QoS) -> None:
        self.shared = shared
        self.wake = wake
        self.depth = qos.depth
        self.blocking = qos.blocks_publisher
        self.items: deque[Any] = deque()
        self.dropped = 0  # keep_last: replaced in this branch before its subscription took them

    def try_take(self) -> Any | None:
        if not self.items:
            self.shared.fill(self)
        try:
            item = self.items.popleft()
        except IndexError:
            return None
        if self.blocking:  # room freed here: what waited behind a full branch can move on
            self.shared.fill(self)
        if self.items:
            # fill() wakes the other branches, not the taker; a caller that takes one message per
            # wake (the executor's polling spin) would leave the rest here when the stream stops
            self.wake()
        return item

    def pending(self) -> bool:
        return bool(self.items) or self.shared.inner.pending()

    def liveliness(self) -> tuple[int, int] | None:
        return self.shared.inner.liveliness()

    def counters(self) -> dict[str, int]:
        merged = dict(self.shared.inner.counters())
        if self.dropped:
            merged["dropped"] = merged.get("dropped", 0) + self.dropped
        return merged

    def close(self) -> None:
        self.shared.remove(self)
