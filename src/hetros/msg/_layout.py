"""Flat layouts: a message type's primitives at fixed offsets, as a numpy dtype.

fpgaDDS streams a nested message as its flattened primitives; hetros does the
same for memory. The layout follows CDR (little endian) exactly: each
primitive aligned to its size relative to the start of the CDR body. So for a
fixed-size type, the CDR bytes *are* the flat record: a subscriber can read
fields straight from a shared-memory slot with ``np.frombuffer(..., dtype)``,
no deserialization. Fields after the first variable-length one (a string or
a sequence) have data-dependent offsets and are reported as variable.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype

if TYPE_CHECKING:
    from ._registry import TypeRegistry

_SIZES = {
    "bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2,
    "int32": 4, "uint32": 4, "int64": 8, "uint64": 8, "float32": 4, "float64": 8,
}
_NUMPY = {
    "bool": "?", "byte": "u1", "char": "u1", "int8": "i1", "uint8": "u1", "int16": "<i2", "uint16": "<u2",
    "int32": "<i4", "uint32": "<u4", "int64": "<i8", "uint64": "<u8", "float32": "<f4", "float64": "<f8",
}


@dataclass(frozen=True)
class LayoutField:
    """One flattened primitive (or fixed array of primitives)."""

    path: str
    type: str
    offset: int | None
    size: int | None
    count: int = 1

    @property
    def variable(self) -> bool:
        return self.offset is None


@dataclass(frozen=True)
class ArrayField:
    """A primitive array a transport can place in shared memory (zero-copy)."""

    path: tuple[str, ...]
    dtype: np.dtype[Any]
    length: int | None


@dataclass(frozen=True)
class FlatLayout:
    typename: str
    fields: tuple[LayoutField, ...]

    @property
    def fixed_size(self) -> bool:
        return all(not f.variable for f in self.fields)

    @property
    def size(self) -> int | None:
        """Bytes of the CDR body when every field is fixed, else None."""
        if not self.fixed_size or not self.fields:
            return 0 if not self.fields else None
        last = self.fields[-1]
        assert last.offset is not None and last.size is not None
        return last.offset + last.size

    @property
    def dtype(self) -> np.dtype[Any]:
        """Structured dtype of the fixed prefix (every field before the first variable one)."""
        names: list[str] = []
        formats: list[Any] = []
        offsets: list[int] = []
        end = 0
        for field in self.fields:
            if field.variable:
                break
            assert field.offset is not None and field.size is not None
            names.append(field.path)
            fmt = _NUMPY[field.type]
            formats.append((fmt, (field.count,)) if field.count > 1 else fmt)
            offsets.append(field.offset)
            end = field.offset + field.size
        return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": end})

    def view(self, cdr: bytes | memoryview) -> np.ndarray[Any, Any]:
        """The fixed prefix of CDR bytes (with their 4-byte encapsulation) as one record."""
        return np.frombuffer(cdr, dtype=self.dtype, count=1, offset=4)[0]  # type: ignore[no-any-return]

    def describe(self) -> str:
        lines = [f"{self.typename}: "
                 + (f"fixed size, {self.size} bytes (CDR body)" if self.fixed_size else "variable size")]
        lines.append(f"  {'offset':>7} {'size':>6}  {'type':<12} field")
        for f in self.fields:
            offset = "var" if f.offset is None else str(f.offset)
            size = "var" if f.size is None else str(f.size)
            kind = f.type + (f"[{f.count}]" if f.count > 1 else "")
            lines.append(f"  {offset:>7} {size:>6}  {kind:<12} {f.path}")
        return "\n".join(lines)


def flat_layout(types: TypeRegistry, typename: str) -> FlatLayout:
    """Flatten ``typename`` into primitives with CDR offsets."""
    fields: list[LayoutField] = []
    _flatten(types, types.get(typename).__msgtype__, "", [0], fields)
    return FlatLayout(types.get(typename).__msgtype__, tuple(fields))


def _align(pos: int, size: int) -> int:
    return (pos + size - 1) & -size


def _flatten(types: TypeRegistry, typename: str, prefix: str, cursor: list[int | None],
             out: list[LayoutField]) -> None:
    fields: Any = types.fielddefs[typename][1]
    for name, desc in fields:
        path = prefix + name
        kind, arg = desc
        pos = cursor[0]
        if kind == Nodetype.NAME:
            _flatten(types, arg, path + ".", cursor, out)
            continue
        if kind == Nodetype.BASE:
            base = arg[0]
            if base == "string":
                out.append(LayoutField(path, "string", None, None))
                cursor[0] = None
                continue
            size = _SIZES[base]
            start = None if pos is None else _align(pos, size)
            out.append(LayoutField(path, base, start, None if start is None else size))
            cursor[0] = None if start is None else start + size
            continue
        sub, length = arg
        if kind == Nodetype.ARRAY and sub[0] == Nodetype.BASE and sub[1][0] != "string":
            size = _SIZES[sub[1][0]]
            start = None if pos is None else _align(pos, size)
            out.append(LayoutField(path, sub[1][0], start, None if start is None else size * length, length))
            cursor[0] = None if start is None else start + size * length
            continue
        element = sub[1][0] if sub[0] == Nodetype.BASE else str(sub[1])
        suffix = f"[{length}]" if kind == Nodetype.ARRAY else "[]"
        out.append(LayoutField(path, element + suffix, None, None))
        cursor[0] = None


def get_path(message: Any, path: tuple[str, ...]) -> Any:
    """The field at ``path`` (an ArrayField's path: attribute names through nested messages)."""
    for name in path:
        message = getattr(message, name)
    return message


def set_path(message: Any, path: tuple[str, ...], value: object) -> None:
    """Set the field at ``path``; works on read-only (frozen) messages too, for transports."""
    holder = message
    for name in path[:-1] if len(path) > 1 else ():  # a top-level field (most loans) walks nothing
        holder = getattr(holder, name)
    object.__setattr__(holder, path[-1], value)


def array_fields(types: TypeRegistry, typename: str) -> list[ArrayField]:
    """Primitive arrays reachable through nested messages (not inside sequences of messages)."""
    found: list[ArrayField] = []
    _arrays(types, types.get(typename).__msgtype__, (), found)
    return found


def _arrays(types: TypeRegistry, typename: str, prefix: tuple[str, ...], out: list[ArrayField]) -> None:
    cls = types.get(typename)
    fields: Any = types.fielddefs[typename][1]
    for attr, (_name, desc) in zip(cls.__fieldnames__, fields, strict=True):
        kind, arg = desc
        if kind == Nodetype.NAME:
            _arrays(types, arg, (*prefix, attr), out)
        elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
            sub, length = arg
            if sub[0] == Nodetype.BASE and sub[1][0] != "string":
                out.append(ArrayField((*prefix, attr), np.dtype(_NUMPY[sub[1][0]]),
                                      length if kind == Nodetype.ARRAY else None))
