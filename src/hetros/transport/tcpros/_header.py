"""TCPROS connection headers: the one message each side sends when a connection opens.

A header is a 4-byte little-endian length, then fields, each a 4-byte little-endian
length and ``name=value`` (the value may hold ``=`` and any bytes). rospy and roscpp send
``callerid``, ``topic``, ``md5sum``, ``type``, ``message_definition`` and optionally
``tcp_nodelay`` when subscribing, ``latching`` when answering, ``service``,
``persistent`` and ``probe`` for services, and ``error`` to refuse.

After the headers every message is a frame: a 4-byte little-endian length (``FRAME``)
and that many bytes, refused above ``MAX_FRAME``.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping

from ..._errors import ProtocolError

_LENGTH = struct.Struct("<I")
# no stock node sends more; a larger length is garbage or an attack, never a buffer to allocate
MAX_HEADER = 1 << 20
FRAME = struct.Struct("<I")
# a frame longer than this is refused
MAX_FRAME = 1 << 30


def encode_header(fields: Mapping[str, str]) -> bytes:
    """The header with its leading length, fields in the order given."""
    parts = []
    for name, value in fields.items():
        if not name or "=" in name:
            raise ValueError(f"TCPROS header field name must be non-empty without '=', not {name!r}")
        field = f"{name}={value}".encode()
        parts.append(_LENGTH.pack(len(field)) + field)
    body = b"".join(parts)
    return _LENGTH.pack(len(body)) + body


def header_length(prefix: bytes, peer: str) -> int:
    """The length the first 4 bytes announce, checked against ``MAX_HEADER``."""
    (length,) = _LENGTH.unpack(prefix)
    if length > MAX_HEADER:
        raise ProtocolError(f"{peer}: the connection header announces {length} bytes (more than {MAX_HEADER}); "
                            "this peer does not speak TCPROS")
    return int(length)


def decode_header(body: bytes, peer: str) -> dict[str, str]:
    """Fields of a header body (what follows its length); ``peer`` names the sender in errors.

    Offsets in errors count from the start of the header, its length included.
    """
    fields: dict[str, str] = {}
    pos = 0
    while pos < len(body):
        if pos + 4 > len(body):
            raise ProtocolError(f"{peer}: connection header field at offset {pos + 4} is cut off "
                                f"({len(body) - pos} of its 4 length bytes)")
        (length,) = _LENGTH.unpack_from(body, pos)
        start, end = pos + 4, pos + 4 + length
        if end > len(body):
            raise ProtocolError(f"{peer}: connection header field at offset {pos + 4} claims {length} bytes, "
                                f"but the header ends {len(body) - start} bytes later")
        raw = body[start:end]
        name, equals, value = raw.partition(b"=")
        if not equals or not name:
            raise ProtocolError(f"{peer}: connection header field at offset {pos + 4} is not name=value: "
                                f"{raw[:40]!r}")
        try:
            key, text = name.decode(), value.decode()
        except UnicodeDecodeError as exc:
            raise ProtocolError(f"{peer}: connection header field at offset {pos + 4} is not UTF-8: "
                                f"{exc.reason}") from None
        if key in fields:
            raise ProtocolError(f"{peer}: connection header field {key!r} at offset {pos + 4} appears twice")
        fields[key] = text
        pos = end
    return fields


def require(fields: Mapping[str, str], names: tuple[str, ...], peer: str) -> None:
    """Refuse a header that lacks one of ``names`` (naming what came instead)."""
    missing = [name for name in names if name not in fields]
    if missing:
        error = f"; it says: {fields['error']}" if "error" in fields else ""
        raise ProtocolError(f"{peer}: connection header lacks {', '.join(missing)} "
                            f"(it has {', '.join(sorted(fields)) or 'nothing'}){error}")


def frame_length(length: int, peer: str, limit: int = MAX_FRAME) -> int:
    """``length`` as a frame announces it, refused above ``limit`` (garbage must not become an allocation)."""
    if length > limit:
        raise ProtocolError(f"{peer}: a frame announces {length} bytes (more than {limit})")
    return int(length)
