"""Transports: what carries an edge of the plan.

The runtime opens them through the registry of ``_seam`` and never names one: ``inproc``
(the object itself, here), ``shm`` (iceoryx2 shared memory), ``dds`` (CycloneDDS, between
hosts) and ``tcpros`` (ROS 1 nodes) are sub-packages imported on first use, so a process
loads only the transports its edges use. The shared-memory names below are re-exported
lazily for the same reason.
"""

from typing import TYPE_CHECKING, Any

from .._qos import DEFAULT_QOS, QoS
from ._base import Codec, Reader, WaitSource, Wake, Writer
from ._codec import EnvelopeCodec, MessageCodec, carried_message
from ._inproc import InprocTopic, InprocTransport, Mailbox
from ._seam import Endpoint, Transport, TransportContext, register, registered, transport_class

if TYPE_CHECKING:
    from .shm import (
        SESSION_TAG_VARIABLE,
        ShmDomain,
        ShmReader,
        ShmWriter,
        WakeChannel,
        check_room,
        cleanup_stale,
        has_loan,
        new_session,
        raise_open_file_limit,
        remove_session_segments,
        reserved_bytes,
    )

_FROM_SHM = frozenset({
    "SESSION_TAG_VARIABLE", "ShmDomain", "ShmReader", "ShmWriter", "WakeChannel", "check_room", "cleanup_stale",
    "has_loan",
    "new_session", "raise_open_file_limit", "remove_session_segments", "reserved_bytes",
})


def __getattr__(name: str) -> Any:
    if name in _FROM_SHM:
        from . import shm
        return getattr(shm, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "DEFAULT_QOS",
    "SESSION_TAG_VARIABLE",
    "Codec",
    "Endpoint",
    "EnvelopeCodec",
    "InprocTopic",
    "InprocTransport",
    "Mailbox",
    "MessageCodec",
    "QoS",
    "Reader",
    "ShmDomain",
    "ShmReader",
    "ShmWriter",
    "Transport",
    "TransportContext",
    "WaitSource",
    "Wake",
    "WakeChannel",
    "Writer",
    "carried_message",
    "check_room",
    "cleanup_stale",
    "has_loan",
    "new_session",
    "raise_open_file_limit",
    "register",
    "registered",
    "remove_session_segments",
    "reserved_bytes",
    "transport_class",
]
