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
    """One flattened primitive (or fixed array of primitives). Where the offset or size depends on the
    data (after a string or a sequence), ``at`` and ``spans`` say how, as an expression of the lengths
    before it (``a4(12+n1)``: 12 plus the first length, rounded up to a multiple of 4)."""

    path: str
    type: str
    offset: int | None
    size: int | None
    count: int = 1
    at: str = ""
    spans: str = ""

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
        width = max([7, *(len(f.at) for f in self.fields)])
        spans = max([6, *(len(f.spans) for f in self.fields)])
        lines.append(f"  {'offset':>{width}} {'size':>{spans}}  {'type':<12} field")
        for f in self.fields:
            offset = (f.at or "var") if f.offset is None else str(f.offset)
            size = (f.spans or "var") if f.size is None else str(f.size)
            kind = f.type + (f"[{f.count}]" if f.count > 1 else "")
            lines.append(f"  {offset:>{width}} {size:>{spans}}  {kind:<12} {f.path}")
        legend = [f.spans for f in self.fields if f.spans]
        if legend:
            lines.append("  (offsets from the CDR body's start; nK: the K-th length word's value: a string's bytes "
                         "with its NUL, a sequence's elements; aN(x): x rounded up to a multiple of N)")
        return "\n".join(lines)


def flat_layout(types: TypeRegistry, typename: str) -> FlatLayout:
    """Flatten ``typename`` into primitives with CDR offsets."""
    fields: list[LayoutField] = []
    _flatten(types, types.get(typename).__msgtype__, "", [0], fields)
    return FlatLayout(types.get(typename).__msgtype__, tuple(_symbolic(fields)))


def _symbolic(fields: list[LayoutField]) -> list[LayoutField]:
    """``fields`` with the data-dependent offsets and sizes written as expressions (``at``, ``spans``): each
    string or sequence adds its length word's value (``n1``, ``n2``...), and each field starts where CDR
    aligns it. A field whose shape cannot be written so (a sequence of strings or messages) ends them."""
    out: list[LayoutField] = []
    cursor = _Cursor()
    lengths = 0
    for field in fields:
        if field.offset is not None and field.size is not None and not cursor.base:
            out.append(field)
            cursor.const = field.offset + field.size
            continue
        if cursor.stopped:
            out.append(field)
            continue
        element = 1 if field.type == "string" else _SIZES.get(field.type.removesuffix("[]"), 0)
        if field.type == "string" or (field.type.endswith("[]") and element):
            start = cursor.align(4)
            lengths += 1
            name = f"n{lengths}"
            items = name if element == 1 else f"{name}*{element}"
            if element > 4:
                cursor.const += 4
                cursor.align(8)
                out.append(LayoutField(field.path, field.type, None, None, field.count, start, f"4+pad+{items}"))
            else:
                out.append(LayoutField(field.path, field.type, None, None, field.count, start, f"4+{items}"))
                cursor.const += 4
            cursor.add(items, element)
            continue
        size = _SIZES.get(field.type)
        if size is None:  # a sequence of strings or messages: the offsets after it are not one expression
            out.append(field)
            cursor.stopped = True
            continue
        start = cursor.align(size)
        out.append(LayoutField(field.path, field.type, None, size * field.count, field.count, start))
        cursor.const += size * field.count
    return out


class _Cursor:
    """Where the next field starts: ``base`` (an expression of the lengths, a multiple of ``aligned``)
    plus ``const`` bytes."""

    def __init__(self) -> None:
        self.base = ""
        self.const = 0
        self.aligned = 8
        self.stopped = False

    def text(self) -> str:
        if not self.base:
            return str(self.const)
        return f"{self.base}+{self.const}" if self.const else self.base

    def align(self, size: int) -> str:
        """Move to the next multiple of ``size`` (at most 8, as CDR aligns) and say where that is."""
        need = min(size, 8)
        if not self.base:
            self.const = _align(self.const, need)
        elif need > self.aligned or self.const % need:
            if need <= self.aligned:
                self.const = _align(self.const, need)
            else:
                self.base, self.const, self.aligned = f"a{need}({self.text()})", 0, need
        return self.text()

    def add(self, items: str, element: int) -> None:
        """Past ``items`` bytes known only from the data, each element ``element`` bytes wide."""
        self.base = f"{self.text()}+{items}" if self.base or self.const else items
        self.const = 0
        self.aligned = min(element, 8)


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
