"""Codecs that turn messages (and service envelopes) into bytes for shared memory."""

from __future__ import annotations

import struct
from typing import Any, NoReturn

from .._errors import SerializationError
from ..msg import ArrayField, Message, TypeRegistry, array_fields
from ._base import Codec

CDR_LE = b"\x00\x01\x00\x00"


class MessageCodec(Codec):
    """CDR, little endian with the 4-byte encapsulation header: the ROS 2 wire format.

    The type's generated codec does the work (``msg.TypeRegistry.codec``); decoded
    messages are read-only and their primitive arrays are views on the bytes.
    """

    def __init__(self, registry: TypeRegistry, typename: str) -> None:
        self.typename = typename
        self._registry = registry
        self.cls = registry.get(typename)
        self._cdr = registry.codec(typename)
        self._arrays: list[ArrayField] | None = None
        # a decoded message keeps no view on its bytes (see ``msg.CdrCodec``)
        self.decode_copies = self._cdr.decode_copies
        # the generated functions, held directly: every transport's hot path runs through here.
        # They see the body alone: ``body_size(message)``, ``encode_body(message, buffer, at)``
        # after the caller wrote the encapsulation, ``decode_body(buffer, at, end)`` after it checked it.
        self.body_size, self.encode_body, self.decode_body = self._cdr.size, self._cdr.encode, self._cdr.decode

    @property
    def arrays(self) -> list[ArrayField]:
        """The primitive arrays a loan can place in shared memory, in a fixed order."""
        if self._arrays is None:
            self._arrays = array_fields(self._registry, self.typename)
        return self._arrays

    def size(self, message: Any) -> int:
        return 4 + self.body_size(message)

    def encode_into(self, message: Any, buffer: memoryview) -> None:
        buffer[:4] = CDR_LE
        self.encode_body(message, buffer[4:])

    def encode(self, message: Any) -> bytearray:
        """The message's CDR bytes, encapsulation included, in a buffer of their own."""
        buffer = bytearray(self.size(message))
        self.encode_into(message, memoryview(buffer))
        return buffer

    def decode_at(self, buffer: memoryview, at: int, end: int) -> Message:
        """Decode ``buffer[at:end]`` in place (``at + 4`` must be a multiple of 8)."""
        if end - at < 4 or buffer[at + 1] != 1:
            self._refuse_encapsulation(buffer, at, end)
        return self.decode_body(buffer, at + 4, end)  # type: ignore[no-any-return]

    def _refuse_encapsulation(self, buffer: memoryview, at: int, end: int) -> NoReturn:
        raise SerializationError(
            f"{self.typename}: {end - at} bytes do not start with the little-endian CDR "
            f"encapsulation 00 01 (got {bytes(buffer[at:min(at + 4, end)]).hex(' ') or 'nothing'})"
        )

    def lean_size(self, message: Any) -> int:
        """The size with every variable-length primitive array (``arrays``) left empty."""
        return 4 + self._cdr.size_lean(message)

    def encode_lean_at(self, message: Any, buffer: memoryview, at: int, end: int) -> None:
        """Encode at ``at`` with every variable-length primitive array left empty (they travel
        beside); raises ``ValueError`` when it does not fit before ``end``."""
        buffer[at:at + 4] = CDR_LE
        self._cdr.encode_lean(message, buffer[:end], at + 4)  # the bound makes an overflow raise

    def decode(self, data: memoryview) -> Message:
        """Decode CDR into a read-only message; primitive arrays are views on ``data`` (no copy)."""
        if len(data) < 4 or data[1] != 1:
            self._refuse_encapsulation(data, 0, len(data))
        return self.decode_body(data[4:])  # type: ignore[no-any-return]


_ENVELOPE = struct.Struct("<QH")


def carried_message(item: Any) -> Message | None:
    """The message an item on a channel carries: the item itself, or a service envelope's message.

    Service channels move envelopes ``(request id, client name, message)`` (see EnvelopeCodec).
    """
    if isinstance(item, Message):
        return item
    if isinstance(item, tuple) and item and isinstance(item[-1], Message):
        return item[-1]
    return None


class EnvelopeCodec(Codec):
    """A service request or reply: (request id, client name, message)."""

    def __init__(self, inner: MessageCodec) -> None:
        self._inner = inner

    def size(self, envelope: Any) -> int:
        _request_id, client, message = envelope
        return _ENVELOPE.size + len(client.encode()) + self._inner.size(message)

    def encode_into(self, envelope: Any, buffer: memoryview) -> None:
        request_id, client, message = envelope
        name = client.encode()
        _ENVELOPE.pack_into(buffer, 0, request_id, len(name))
        start = _ENVELOPE.size
        buffer[start:start + len(name)] = name
        self._inner.encode_into(message, buffer[start + len(name):])

    def decode(self, data: memoryview) -> tuple[int, str, Message]:
        if len(data) < _ENVELOPE.size:
            raise SerializationError(
                f"service envelope of {len(data)} bytes is shorter than its {_ENVELOPE.size}-byte header"
            )
        request_id, length = _ENVELOPE.unpack_from(data, 0)
        start = _ENVELOPE.size
        client = bytes(data[start:start + length]).decode()
        return request_id, client, self._inner.decode(data[start + length:])
