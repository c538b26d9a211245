"""Transports: inproc (the object itself), shm (iceoryx2 shared memory)."""

from ._base import Codec, Reader, Wake, Writer
from ._codec import EnvelopeCodec, MessageCodec, carried_message
from ._inproc import InprocTopic, Mailbox
from ._qos import DEFAULT_QOS, QoS
from .shm import (
    SESSION_TAG_VARIABLE,
    ShmDomain,
    ShmReader,
    ShmWriter,
    WakeChannel,
    cleanup_stale,
    has_loan,
    new_session,
    raise_open_file_limit,
    remove_session_segments,
    reserved_bytes,
)

__all__ = [
    "DEFAULT_QOS",
    "SESSION_TAG_VARIABLE",
    "Codec",
    "EnvelopeCodec",
    "InprocTopic",
    "Mailbox",
    "MessageCodec",
    "QoS",
    "Reader",
    "ShmDomain",
    "ShmReader",
    "ShmWriter",
    "Wake",
    "WakeChannel",
    "Writer",
    "carried_message",
    "cleanup_stale",
    "has_loan",
    "new_session",
    "raise_open_file_limit",
    "remove_session_segments",
    "reserved_bytes",
]
