"""What every transport provides: writers that deliver, readers that take.

A reader never calls user code. When data may be available its ``wake``
function runs (for shared memory, in the thread that waits on the node's wake
channel; in-process, in the publishing thread); the runtime then takes
messages in the node's own thread. That keeps the executor the only place
where callbacks run, whatever the transport.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any, Generic, Protocol

from typing_extensions import TypeVar

Wake = Callable[[], None]
# what a writer carries and a reader delivers: a message, or a service envelope
# ``(request_id, client, message)``; Any where one endpoint serves every type
T = TypeVar("T", default=Any)


class WaitSource(Protocol):
    """What a node's executor can block on besides its own condition (a transport's wake channel,
    a ROS 1 node's sockets): the transport that owns it runs each reader's wake function."""

    def wait(self, timeout: float | None) -> None:
        """Block until an event or ``timeout``, then run the wake function of each reader that fired."""
        ...

    def interrupt(self) -> None:
        """Make a blocked ``wait`` return (from any thread)."""
        ...

    def poll(self) -> None:
        """Without blocking, run the wake function of each reader that has data now."""
        ...


class Writer(ABC, Generic[T]):
    """Publishing end of one topic (or service channel) for one endpoint.

    A writer gets messages already handed over (frozen, arrays the caller still owns copied
    or marked): the runtime applies that ownership rule once, above every transport.
    """

    # whether the transport lends its own memory for messages to be filled in place
    # (``slot_loan_maker``, ``owns_loan``): shared memory does, in-process delivery need not
    lends_slots = False
    # whether a reader gets the written object itself (in-process delivery); every other writer has
    # serialized the message when ``write`` returns, so its caller may go on changing it
    shares_objects = False

    @abstractmethod
    def write(self, message: T) -> None:
        """Deliver ``message`` to every subscriber; may block per QoS, then raise."""

    def slot_loan_maker(self, sizes: dict[str, int]) -> Callable[[], Any] | None:
        """What makes messages of these array lengths whose arrays live in the transport's
        memory (a zero-copy publish), or None where a loan there does not pay."""
        return None

    def owns_loan(self, message: Any) -> bool:
        """Whether ``message`` came from ``slot_loan_maker`` and has not been published yet."""
        return False

    def has_room(self) -> bool:
        """Whether a write now would go through without waiting for a reliable subscriber's room. One
        sender that serves several streams (an fpga target's gateway) asks before it writes, so that a
        full subscriber holds back only its own stream; a transport whose writes never wait says True."""
        return True

    def counters(self) -> dict[str, int]:
        """What ``hetros top`` shows of this writer: ``stalls``, the sends that waited for a reliable
        subscriber's room, and ``bytes`` serialized (where it serializes); empty where it does not count."""
        return {}

    def assert_liveliness(self) -> None:
        """Say this publisher is alive (a ``manual_by_topic`` topic's publish says it too);
        a transport that cannot tell liveliness has nothing to record."""
        return None

    @abstractmethod
    def close(self) -> None: ...


class Reader(ABC, Generic[T]):
    """Subscribing end; ``try_take`` returns the next message or None when empty.

    What a reader delivers is read-only (a frozen message whose arrays are not writeable):
    it may be the publisher's own object, or a view on shared memory. A damaged or lost
    message raises (:class:`~hetros.TransportError`); None only ever means "nothing now".
    """

    @abstractmethod
    def try_take(self) -> T | None: ...

    def taker(self) -> Callable[[], T | None]:
        """The function a frequent caller keeps and calls instead of ``try_take``.

        It takes exactly as ``try_take`` does; a reader whose fastest path depends on how it
        was opened (one publisher, a compiled decoder) or that only wraps another returns
        that path here, so the hot loop makes one call per message and no method is
        rebound on an instance.
        """
        return self.try_take

    def pending(self) -> bool:
        """Whether a ``try_take`` now may find a message: False only when the reader knows its
        FIFO is empty.

        The executor asks after each callback whether to queue the subscription again; an
        empty take costs more than this answer. A message that arrives after a False still
        wakes the reader as usual.
        """
        return True

    def liveliness(self) -> tuple[int, int] | None:
        """(alive, not alive): the publishers this reader has heard from, by the topic's
        liveliness QoS; None where the transport cannot tell."""
        return None

    def counters(self) -> dict[str, int]:
        """What ``hetros top`` shows of this reader: ``dropped``, keep_last messages replaced by newer
        ones before they were taken; empty where the transport does not count."""
        return {}

    @abstractmethod
    def close(self) -> None: ...


class Codec(ABC):
    """Turns messages into bytes for transports that cross a process boundary."""

    @abstractmethod
    def size(self, message: Any) -> int: ...

    @abstractmethod
    def encode_into(self, message: Any, buffer: memoryview) -> None: ...

    @abstractmethod
    def decode(self, data: memoryview) -> Any: ...
