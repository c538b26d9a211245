"""A message as the beats of a hardware stream, and back.

The beat stream of a message is its CDR body (little endian, CDR-aligned, string and
sequence lengths inline, no 4-byte encapsulation header) byte for byte, whatever the type
(the network cuts messages at TLAST and parses nothing; a node reads what it needs), cut into beats of
``data_width`` bits: byte ``k`` of a beat sits at ``tdata[8k+7:8k]``, TLAST marks the last
beat, and TKEEP (one bit per byte) marks which bytes of it count. So a gateway between
software and hardware is a copy, and the CDR bytes rosbags writes are the reference.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._errors import HardwareError, SerializationError
from ...msg import TypeRegistry, normalize_typename

_ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little endian


@dataclass(frozen=True)
class Beats:
    """A message's beats: ``data`` (beats x bytes per beat, uint8) and ``keep`` (TKEEP of each beat)."""

    data: np.ndarray[Any, np.dtype[np.uint8]]
    keep: np.ndarray[Any, np.dtype[np.uint64]]

    def __len__(self) -> int:
        return int(self.data.shape[0])

    def words(self) -> list[int]:
        """Each beat's TDATA as an integer (byte 0 in the low bits), for simulators."""
        return [int.from_bytes(row.tobytes(), "little") for row in self.data]


def to_beats(body: bytes | memoryview | np.ndarray[Any, Any], data_width: int) -> Beats:
    """Cut a CDR body into beats of ``data_width`` bits (vectorised: one pad, one reshape)."""
    per_beat = _bytes_per_beat(data_width)
    raw = np.frombuffer(body, np.uint8) if not isinstance(body, np.ndarray) else body.reshape(-1).view(np.uint8)
    if raw.size == 0:
        raise HardwareError("a message stream needs at least one byte; a CDR body always has one")
    count = -(-raw.size // per_beat)
    padded = np.zeros(count * per_beat, np.uint8)
    padded[:raw.size] = raw
    keep = np.full(count, (1 << per_beat) - 1, np.uint64)
    keep[-1] = (1 << (raw.size - (count - 1) * per_beat)) - 1
    return Beats(padded.reshape(count, per_beat), keep)


def from_beats(beats: Beats) -> bytes:
    """The bytes the beats carry: every full beat, and the kept bytes of the last one."""
    if len(beats) == 0:
        raise HardwareError("no beats: a message stream ends with a beat with TLAST")
    per_beat = beats.data.shape[1]
    last = int(beats.keep[-1])
    if last == 0 or last & (last + 1):
        raise HardwareError(f"TKEEP of the last beat must be contiguous low bytes (0b0..01..1), not {last:#b}")
    if np.any(beats.keep[:-1] != (1 << per_beat) - 1):
        raise HardwareError("only the last beat of a message may be partial (TKEEP all ones before it)")
    return beats.data[:-1].tobytes() + beats.data[-1, :last.bit_length()].tobytes()


def _bytes_per_beat(data_width: int) -> int:
    if data_width < 8 or data_width % 8 or data_width > 1024:
        raise HardwareError(f"data_width must be a multiple of 8 bits from 8 to 1024, not {data_width!r}")
    return data_width // 8


class BeatCodec:
    """One message type to and from beats, through its CDR body (rosbags writes and reads it)."""

    def __init__(self, types: TypeRegistry, typename: str, data_width: int) -> None:
        self.typename = normalize_typename(typename)
        self.data_width = data_width
        _bytes_per_beat(data_width)
        self._types = types

    def body(self, message: Any) -> bytes:
        return bytes(self._types.store.serialize_cdr(message, self.typename))[len(_ENCAPSULATION):]

    def pack(self, message: Any) -> Beats:
        return to_beats(self.body(message), self.data_width)

    def unpack(self, beats: Beats) -> Any:
        data = _ENCAPSULATION + from_beats(beats)
        try:
            return self._types.store.deserialize_cdr(data, self.typename)
        except Exception as exc:  # rosbags raises several kinds for bad bytes
            raise SerializationError(f"{len(data) - 4} bytes of beats do not decode as {self.typename}: "
                                     f"{exc}") from exc


_SIGNED = {"int8", "int16", "int32", "int64"}
_BITS = {"bool": 8, "byte": 8, "char": 8, "int8": 8, "uint8": 8, "int16": 16, "uint16": 16, "int32": 32,
         "uint32": 32, "int64": 64, "uint64": 64, "float32": 32, "float64": 64}


def field_name(path: str) -> str:
    """``header.stamp.sec`` -> ``header__stamp__sec``: a flattened field as an Amaranth field name."""
    return path.replace(".", "__")


def amaranth_layout(types: TypeRegistry, typename: str) -> Any:
    """The fixed part of a message's beat stream as an Amaranth ``StructLayout`` (for hardware nodes).

    Its fields sit at the bit offsets of the CDR body (padding included, as ``_pad<offset>``),
    so a ``View`` of this layout over the first beats, concatenated in order, reads the
    fields a node needs without a parser. Floats are their IEEE-754 bits; everything from
    the first string or sequence on has data-dependent offsets and is left out.
    """
    from amaranth import signed, unsigned
    from amaranth.lib import data

    from ...msg import flat_layout

    fields: dict[str, Any] = {}
    cursor = 0
    for item in flat_layout(types, typename).fields:
        if item.variable:
            break
        assert item.offset is not None
        if item.offset > cursor:
            fields[f"_pad{cursor}"] = unsigned(8 * (item.offset - cursor))
        bits = _BITS[item.type]
        shape = signed(bits) if item.type in _SIGNED else unsigned(bits)
        fields[field_name(item.path)] = data.ArrayLayout(shape, item.count) if item.count > 1 else shape
        cursor = item.offset + bits // 8 * item.count
    return data.StructLayout(fields)
