"""MCAP files checked as hetros writes and plays them: chunk CRCs written, damage named, what is whole played.

rosbags writes chunks without a CRC (0, "not set"), so a bit flipped on disk played as valid
data; a truncated file ended `hetros play` in a traceback. After recording, :func:`seal`
writes each chunk's CRC-32 of its uncompressed records, the data section's CRC and the
summary's (as the MCAP specification defines them). Before playing, :func:`check` walks the
file record by record, never trusting a length: it names the first damaged chunk (its index
and offset), where a truncated file stops, and how many messages each damaged chunk held (from
its message index). :func:`whole_messages` then yields the messages of the whole chunks only.
"""

from __future__ import annotations

import mmap
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

MAGIC = b"\x89MCAP0\r\n"
_HEADER, _FOOTER, _SCHEMA, _CHANNEL, _MESSAGE, _CHUNK, _MESSAGE_INDEX, _DATA_END = 0x01, 0x02, 0x03, 0x04, 0x05, \
    0x06, 0x07, 0x0F
_RECORD = struct.Struct("<BQ")
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_CHUNK_HEAD = struct.Struct("<QQQI")  # start, end, uncompressed size, uncompressed CRC
_FOOTER_BODY = struct.Struct("<QQI")  # summary start, summary offset start, summary CRC
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel, sequence, log time, publish time


class _Broken(Exception):
    def __init__(self, offset: int, why: str) -> None:
        super().__init__(why)
        self.offset = offset
        self.why = why


@dataclass
class Damage:
    """A chunk that cannot be played: which one, where, why, and what it held."""

    chunk: int
    offset: int
    why: str
    messages: int | None  # from its message index; None when that is damaged too

    def describe(self) -> str:
        held = f"its {self.messages} messages skipped" if self.messages is not None else "its messages skipped " \
                                                                                           "(how many is unknown)"
        return f"chunk {self.chunk} at offset {self.offset} is damaged ({self.why}): {held}"


@dataclass
class Check:
    """What :func:`check` found in one file."""

    path: Path
    chunks: int = 0
    messages: int = 0  # in whole chunks
    damaged: list[Damage] = field(default_factory=list)
    truncated_at: int | None = None  # where the file stops being readable
    other: list[str] = field(default_factory=list)  # damage outside chunks (header, indexes, summary)

    @property
    def whole(self) -> bool:
        return not self.damaged and self.truncated_at is None and not self.other

    def lines(self) -> list[str]:
        found = [f"{self.path}: {damage.describe()}" for damage in self.damaged]
        found += [f"{self.path}: {problem}" for problem in self.other]
        if self.truncated_at is not None:
            found.append(f"{self.path}: the recording stops at offset {self.truncated_at} (truncated, or a length "
                         f"there is damaged): {self.chunks} chunks before it are played")
        return found


def _string(data: memoryview, at: int, end: int) -> tuple[str, int]:
    if at + 4 > end:
        raise _Broken(at, "a string runs past its record")
    size = _U32.unpack_from(data, at)[0]
    if at + 4 + size > end:
        raise _Broken(at, f"a string of {size} bytes runs past its record")
    return bytes(data[at + 4:at + 4 + size]).decode("utf-8", "replace"), at + 4 + size


def _records(data: memoryview, start: int, end: int) -> Iterator[tuple[int, int, int, int]]:
    """(opcode, record offset, body start, body end) of each record in ``start..end``; _Broken where one
    does not fit."""
    at = start
    while at < end:
        if at + _RECORD.size > end:
            raise _Broken(at, "a record's opcode and length are cut off")
        op, length = _RECORD.unpack_from(data, at)
        body = at + _RECORD.size
        if length > end - body:
            raise _Broken(at, f"a record of {length} bytes (opcode {op:#04x}) runs past the end")
        yield op, at, body, body + length
        at = body + length


def _chunk_records(data: memoryview, body: int, end: int) -> tuple[int, int, memoryview]:
    """A chunk's (uncompressed size, CRC, records), decompressed when it is compressed."""
    if body + _CHUNK_HEAD.size > end:
        raise _Broken(body, "a chunk's header is cut off")
    _start, _end, size, crc = _CHUNK_HEAD.unpack_from(data, body)
    compression, at = _string(data, body + _CHUNK_HEAD.size, end)
    if at + 8 > end:
        raise _Broken(at, "a chunk's records length is cut off")
    length = _U64.unpack_from(data, at)[0]
    if length > end - at - 8:
        raise _Broken(at, f"a chunk claims {length} bytes of records, past its record")
    raw = memoryview(bytes(data[at + 8:at + 8 + length]))  # a copy: the file's mapping is closed after the walk
    if compression == "zstd":
        import zstandard

        try:
            raw = memoryview(zstandard.ZstdDecompressor().decompress(bytes(raw), max_output_size=size))
        except zstandard.ZstdError as exc:
            raise _Broken(at, f"its zstd data does not decompress: {exc}") from None
    elif compression == "lz4":
        import lz4.frame

        try:
            raw = memoryview(lz4.frame.decompress(bytes(raw)))
        except RuntimeError as exc:  # lz4 reports bad frames as RuntimeError
            raise _Broken(at, f"its lz4 data does not decompress: {exc}") from None
    elif compression:
        raise _Broken(body, f"compression {compression!r} is not one hetros plays")
    if len(raw) != size:
        raise _Broken(body, f"it holds {len(raw)} bytes of records where its header says {size}")
    return size, crc, raw


def _index_count(data: memoryview, body: int, end: int) -> int:
    if body + 6 > end:
        raise _Broken(body, "a message index is cut off")
    return int(_U32.unpack_from(data, body + 2)[0] // 16)


def _walk(path: Path, data: memoryview, report: Check | None) -> Iterator[tuple[str, str, int, bytes]]:
    """The messages of the whole chunks (topic, type, log time, data); ``report`` gathers what is not whole."""
    if bytes(data[:8]) != MAGIC:
        if report is not None:
            report.other.append("it does not start with MCAP's magic bytes: not an MCAP file")
        return
    schemas: dict[int, str] = {}
    channels: dict[int, tuple[str, int]] = {}
    pending: Damage | None = None  # a damaged chunk whose message indexes follow it
    index = 0
    try:
        for op, offset, body, end in _records(data, 8, len(data) - 8 if bytes(data[-8:]) == MAGIC else len(data)):
            if op == _MESSAGE_INDEX:
                if pending is not None:
                    pending.messages = (pending.messages or 0) + _index_count(data, body, end)
                continue
            pending = None
            if op == _CHUNK:
                index += 1
                try:
                    _size, crc, records = _chunk_records(data, body, end)
                    if crc and zlib.crc32(records) != crc:
                        raise _Broken(offset, "its CRC does not match its records")
                    inner = list(_records(records, 0, len(records)))
                except _Broken as exc:
                    if report is not None:
                        pending = Damage(index, offset, exc.why, None)
                        report.damaged.append(pending)
                    continue
                if report is not None:
                    report.chunks += 1
                for inner_op, _at, inner_body, inner_end in inner:
                    message = _read_inner(records, inner_op, inner_body, inner_end, schemas, channels)
                    if message is not None:
                        channel, log_time, payload = message
                        if channel in channels:
                            topic, schema = channels[channel]
                            if report is not None:
                                report.messages += 1
                            else:
                                yield topic, schemas.get(schema, ""), log_time, payload
            elif op in (_SCHEMA, _CHANNEL):
                _read_inner(data, op, body, end, schemas, channels)
            elif op == _DATA_END:
                crc = _U32.unpack_from(data, body)[0] if end - body >= 4 else 0
                if crc and zlib.crc32(data[:offset]) != crc and report is not None and not report.damaged:
                    report.other.append("its data section does not match its CRC outside any chunk (a header or "
                                        "a message index is damaged)")
            elif op == _FOOTER:
                _check_footer(data, offset, body, end, report)
    except _Broken as exc:
        if report is not None:
            report.truncated_at = exc.offset
    if bytes(data[-8:]) != MAGIC and report is not None and report.truncated_at is None:
        report.truncated_at = len(data)


def _check_footer(data: memoryview, offset: int, body: int, end: int, report: Check | None) -> None:
    if report is None or end - body < _FOOTER_BODY.size:
        return
    start, _offsets, crc = _FOOTER_BODY.unpack_from(data, body)
    if start and not 8 <= start <= offset:
        report.other.append(f"its footer names a summary at offset {start}, outside the file's records: the footer "
                            "is damaged")
    elif crc and start and zlib.crc32(data[start:body + 16]) != crc:
        report.other.append(f"its summary (offset {start}) does not match its CRC: the index is damaged, the "
                            "messages are read without it")


def _read_inner(data: memoryview, op: int, body: int, end: int, schemas: dict[int, str],
                channels: dict[int, tuple[str, int]]) -> tuple[int, int, bytes] | None:
    if op == _SCHEMA:
        if end - body < 2:
            raise _Broken(body, "a schema record is cut off")
        schemas[_U16.unpack_from(data, body)[0]] = _string(data, body + 2, end)[0]
    elif op == _CHANNEL:
        if end - body < 4:
            raise _Broken(body, "a channel record is cut off")
        channel, schema = struct.unpack_from("<HH", data, body)
        channels[channel] = (_string(data, body + 4, end)[0], schema)
    elif op == _MESSAGE:
        if end - body < _MESSAGE_HEAD.size:
            raise _Broken(body, "a message record is cut off")
        channel, _sequence, log_time, _publish = _MESSAGE_HEAD.unpack_from(data, body)
        return channel, log_time, bytes(data[body + _MESSAGE_HEAD.size:end])
    return None


def _mapped(path: Path) -> tuple[mmap.mmap | None, memoryview]:
    with path.open("rb") as handle:
        if path.stat().st_size == 0:
            return None, memoryview(b"")
        mapping = mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ)
    return mapping, memoryview(mapping)


def check(path: Path) -> Check:
    """Walk ``path`` and say what of it is whole (never raises for what the file holds)."""
    report = Check(path)
    mapping, data = _mapped(path)
    try:
        for _ in _walk(path, data, report):
            pass
    finally:
        data.release()
        if mapping is not None:
            mapping.close()
    return report


def whole_messages(path: Path) -> Iterator[tuple[str, str, int, bytes]]:
    """(topic, type, log time, CDR bytes) of every message in the whole chunks of ``path``, in file order."""
    mapping, data = _mapped(path)
    try:
        yield from _walk(path, data, None)
    finally:
        data.release()
        if mapping is not None:
            mapping.close()


def seal(path: Path) -> None:
    """Write the CRCs rosbags leaves at 0: each chunk's, the data section's, the summary's."""
    with path.open("r+b") as handle:
        mapping = mmap.mmap(handle.fileno(), 0)
        data = memoryview(mapping)
        try:
            for op, offset, body, end in _records(data, 8, len(data) - 8):
                if op == _CHUNK:
                    _size, _crc, records = _chunk_records(data, body, end)
                    _U32.pack_into(data, body + 24, zlib.crc32(records))
                elif op == _DATA_END and end - body >= 4:
                    _U32.pack_into(data, body, zlib.crc32(data[:offset]))
                elif op == _FOOTER and end - body >= _FOOTER_BODY.size:
                    start = _U64.unpack_from(data, body)[0]
                    if 0 < start <= offset:
                        _U32.pack_into(data, body + 16, zlib.crc32(data[start:body + 16]))
            mapping.flush()
        finally:
            data.release()
            mapping.close()


def mcap_files(path: Path) -> list[Path]:
    """The MCAP files of a recording: the file itself, or those of a rosbag2 folder."""
    return sorted(path.glob("*.mcap")) if path.is_dir() else [path]
