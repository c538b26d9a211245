"""Generated CDR codecs, one per message type: the hot path of every transport that serializes.

rosbags' codecs are the reference: correct for every type, but they call one
function per nested type, look types up by name on every message, and build
writable messages that must be frozen afterwards. These codecs are generated
per type from the same field definitions, with nested messages inlined, each run
of primitives packed or unpacked by one precompiled ``struct`` (padding included
when it is known at generation time), and decoding that builds read-only
messages directly. The bytes are XCDR1 little endian, byte for byte what rosbags
(and ROS 2) produce; ``tests/unit/test_cdr.py`` cross-checks both directions on
random messages of every shipped type. A type the generator does not cover
(``wstring``) uses rosbags.

Alignment: CDR aligns each primitive to its size, counted from the start of the
body (after the 4-byte encapsulation). The generator tracks what it knows about
the position (``pos % known == 0``) and pads statically while it can; after a
string or a sequence it aligns at run time.
"""

from __future__ import annotations

import struct
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype

from .._errors import SerializationError
from . import _compiled as compiled
from ._layout import array_fields, get_path, set_path
from ._message import FrozenList, copy, freeze

if TYPE_CHECKING:
    from ._registry import TypeRegistry

_FORMATS = {
    "bool": ("?", 1), "byte": ("B", 1), "char": ("B", 1), "int8": ("b", 1), "uint8": ("B", 1),
    "int16": ("h", 2), "uint16": ("H", 2), "int32": ("i", 4), "uint32": ("I", 4),
    "int64": ("q", 8), "uint64": ("Q", 8), "float32": ("f", 4), "float64": ("d", 8),
}
_DTYPES = {
    "bool": "bool", "byte": "uint8", "char": "uint8", "int8": "int8", "uint8": "uint8", "int16": "<i2",
    "uint16": "<u2", "int32": "<i4", "uint32": "<u4", "int64": "<i8", "uint64": "<u8",
    "float32": "<f4", "float64": "<f8",
}

Size = Callable[[Any], int]
Encode = Callable[..., int]
Decode = Callable[..., Any]


class UnsupportedType(Exception):
    """The generator has no code for this field; the type keeps rosbags' codec."""


@dataclass(frozen=True)
class CdrCodec:
    """The CDR body (no encapsulation header) of one message type.

    ``encode(message, buffer, pos=0)`` writes the body at ``pos`` of a writable byte
    memoryview (``size(message)`` bytes) and returns its end; ``decode(buffer, pos=0,
    end=len(buffer))`` returns a read-only message whose primitive arrays are views on
    ``buffer``. CDR aligns relative to the body's start, the code to the buffer's: ``pos``
    must be a multiple of 8 (pass a slice otherwise). The ``lean`` pair encodes
    every variable-length primitive array outside sequences of messages as empty (the
    shared-memory transport sends those arrays beside the body). ``decode_copies`` says
    that a decoded message keeps no view on the buffer (its type has no primitive array),
    so the buffer can be reused as soon as ``decode`` returns.
    """

    typename: str
    size: Size
    encode: Encode
    size_lean: Size
    encode_lean: Encode
    decode: Decode
    generated: bool
    decode_copies: bool = False
    compiled: bool = False


def _lowbit(value: int) -> int:
    return value & -value if value else 8


def _short(where: str, pos: int, need: int, end: int) -> SerializationError:
    return SerializationError(f"{where} at offset {pos} needs {need} bytes, but the message ends at offset {end}")


def _string(buffer: memoryview, pos: int, length: int, end: int, where: str, terminated: bool = True) -> str:
    """A string body at ``pos``: CDR's length counts a NUL terminator, ROS 1's (``terminated=False``) has none."""
    stop = pos + length
    if stop > end or (terminated and length < 1):
        nul = "; a CDR string has at least its NUL" if terminated else ""
        raise SerializationError(f"{where} at offset {pos - 4} has length {length}, which does not fit "
                                 f"the message (ends at offset {end}{nul})")
    if terminated:
        if buffer[stop - 1]:
            raise SerializationError(f"{where} at offset {pos - 4}: string of length {length} does not end in NUL")
        stop -= 1
    try:
        return str(buffer[pos:stop], "utf-8")
    except UnicodeDecodeError as exc:
        raise SerializationError(f"{where} at offset {pos + exc.start} is not UTF-8: {exc.reason}") from None


def _sequence(where: str, pos: int, count: int, bound: int) -> SerializationError:
    return SerializationError(f"{where} at offset {pos} has {count} elements, more than its bound of {bound}")


class _Generator:
    """Writes one kind of function (size, encode or decode) for a type and the types it nests."""

    def __init__(self, types: TypeRegistry, mode: str, lean: bool, namespace: dict[str, Any],
                 ros1: bool = False) -> None:
        self.types = types
        self.mode = mode
        self.lean = lean
        # ROS 1's serialization: CDR's layout without alignment, strings without their NUL
        self.ros1 = ros1
        self.ns = namespace
        self.functions: dict[str, str] = {}
        self._counter = 0
        # whether decode made a view on the buffer (np.frombuffer) anywhere
        self.views = False

    # -- one function ----------------------------------------------------------------------

    def function(self, typename: str, item: bool) -> str:
        """The name of the function for ``typename``; ``item`` variants start at an unknown alignment."""
        flavour = f"{'_ros1' if self.ros1 else ''}{'_lean' if self.lean else ''}{'_item' if item else ''}"
        name = f"_{self.mode}{flavour}_{typename.replace('/', '_')}"
        if name in self.functions:
            return name
        self.functions[name] = ""
        body = _Body(self, item)
        short = typename.rsplit("/", 1)[-1]
        if self.mode == "decode":
            root = body.new_object(typename)
            body.walk(typename, root, short)
            body.flush()
            body.finish_objects()
            head = f"def {name}(buf, pos, end):" if item else \
                f"def {name}(buf, pos=0, end=-1):\n    if end < 0:\n        end = len(buf)"
            tail = f"    return {root}, pos" if item else f"    return {root}"
        else:
            body.walk(typename, "m", short)
            body.flush()
            if self.mode == "size":
                head = f"def {name}(m, pos):" if item else f"def {name}(m):\n    pos = 0"
            else:
                head = f"def {name}(m, buf, pos):" if item else f"def {name}(m, buf, pos=0):"
            tail = "    return pos"
        self.functions[name] = "\n".join([head, *body.lines, tail])
        return name

    def unique(self, prefix: str) -> str:
        self._counter += 1
        return f"{prefix}{self._counter}"

    def constant(self, prefix: str, value: object) -> str:
        name = self.unique(prefix)
        self.ns[name] = value
        return name


class _Body:
    """The statements of one function: a pending run of primitives and what is known of ``pos``."""

    def __init__(self, gen: _Generator, item: bool) -> None:
        self.gen = gen
        self.mode = gen.mode
        self.item = item
        self.lines: list[str] = []
        self.indent = "    "
        self.ros1 = gen.ros1
        self._known = 1 if item else 8
        self.run_format = ""
        self.run_items: list[str] = []
        self.run_length = 0
        self.run_where = ""
        self.objects: list[tuple[str, str]] = []

    @property
    def known(self) -> int:
        """The alignment ``pos`` is known to have (ROS 1 bytes are never aligned: always 8)."""
        return 8 if self.ros1 else self._known

    @known.setter
    def known(self, value: int) -> None:
        self._known = value

    def emit(self, line: str) -> None:
        self.lines.append(self.indent + line)

    # -- runs of primitives ----------------------------------------------------------------

    def primitive(self, fmt: str, size: int, item: str, where: str) -> None:
        if size > self.known:
            self.align(size)
        pad = 0 if self.ros1 else -self.run_length % size
        if not self.run_items:
            self.run_where = where
        self.run_format += "x" * pad + fmt
        self.run_items.append(item)
        self.run_length += pad + size

    def flush(self) -> None:
        if not self.run_length:
            return
        packer = self.gen.constant("_S", struct.Struct("<" + self.run_format))
        if not self.run_items:  # padding alone
            if self.mode == "encode":
                self.emit(f"{packer}.pack_into(buf, pos)")
        elif self.mode == "encode":
            self.emit(f"{packer}.pack_into(buf, pos, {', '.join(self.run_items)})")
        elif self.mode == "decode":
            where = self.gen.constant("_W", self.run_where)
            self.emit(f"if pos + {self.run_length} > end: raise _short({where}, pos, {self.run_length}, end)")
            targets = ", ".join(self.run_items) + ("," if len(self.run_items) == 1 else "")
            self.emit(f"{targets} = {packer}.unpack_from(buf, pos)")
        self.emit(f"pos += {self.run_length}")
        self.known = min(self.known, _lowbit(self.run_length))
        self.run_format, self.run_items, self.run_length = "", [], 0

    def align(self, size: int, condition: str = "") -> None:
        """Align ``pos`` to ``size`` at run time (``condition``: only when it holds)."""
        self.flush()
        if size <= self.known:  # always under ROS 1
            return
        indent = self.indent
        if condition:
            self.emit(f"if {condition}:")
            self.indent += "    "
        if self.mode == "encode":
            # zeros for the padding; the field that follows overwrites the rest
            self.emit(f"buf[pos:pos + {size}] = _Z{size}")
        self.emit(f"pos = (pos + {size - 1}) & -{size}")
        self.indent = indent
        if not condition:
            self.known = size

    # -- objects (decode) ------------------------------------------------------------------

    def new_object(self, typename: str) -> str:
        cls = self.gen.types.get(typename)
        local = self.gen.unique("o")
        thawed = self.gen.constant("_C", cls)
        self.emit(f"{local} = _new({thawed})")
        self.emit(f"{local}._hetros_loan = None")  # as __init__ sets it: a transport reads it unguarded
        self.objects.append((local, self.gen.constant("_F", cls._frozen_class)))
        return local

    def finish_objects(self) -> None:
        for local, frozen in self.objects:
            self.emit(f"{local}.__class__ = {frozen}")

    # -- fields ----------------------------------------------------------------------------

    def walk(self, typename: str, obj: str, where: str) -> None:
        cls = self.gen.types.get(typename)
        _consts, fields = self.gen.types.fielddefs[typename]
        for attr, (_name, desc) in zip(cls.__fieldnames__, fields, strict=True):
            self.field(desc, f"{obj}.{attr}", f"{where}.{attr}")

    def field(self, desc: Any, target: str, where: str) -> None:
        kind, arg = desc
        if kind == Nodetype.BASE:
            if arg[0] == "string":
                self.string(target, where)
            elif arg[0] in _FORMATS:
                fmt, size = _FORMATS[arg[0]]
                self.primitive(fmt, size, target, where)
            else:
                raise UnsupportedType(f"{where}: {arg[0]}")
        elif kind == Nodetype.NAME:
            if self.mode == "decode":
                local = self.new_object(arg)
                self.emit(f"{target} = {local}")
            else:
                local = self.gen.unique("o")
                self.emit(f"{local} = {target}")
            self.walk(arg, local, where)
        else:
            sub, length = arg
            if kind == Nodetype.ARRAY:
                self.fixed_array(sub, length, target, where)
            else:
                self.sequence(sub, length, target, where)

    def string(self, target: str, where: str) -> None:
        nul = 0 if self.ros1 else 1
        if self.mode == "decode":
            length = self.gen.unique("n")
            self.primitive("I", 4, length, where)
            self.flush()
            ros1 = ", False" if self.ros1 else ""
            self.emit(f"{target} = _string(buf, pos, {length}, end, {self.gen.constant('_W', where)}{ros1})")
            self.emit(f"pos += {length}")
        else:
            encoded, size = self.gen.unique("s"), self.gen.unique("k")
            self.emit(f"{encoded} = {target}.encode()")
            self.emit(f"{size} = len({encoded})")
            self.primitive("I", 4, f"{size} + {nul}" if nul else size, where)
            self.flush()
            if self.mode == "encode":
                self.emit(f"buf[pos:pos + {size}] = {encoded}")
                if nul:
                    self.emit(f"buf[pos + {size}] = 0")
            self.emit(f"pos += {size} + {nul}" if nul else f"pos += {size}")
        self.known = 1

    def primitive_block(self, base: str, count: str, static: int | None, target: str, where: str) -> None:
        """``count`` primitives at ``pos`` as one numpy array (aligned by the caller)."""
        _fmt, size = _FORMATS[base]
        nbytes = f"{count} * {size}" if size > 1 else count
        if self.mode == "size":
            self.emit(f"pos += {nbytes}")
        elif self.mode == "encode":
            array = self.gen.unique("a")
            self.emit(f"{array} = {target}")
            if base in ("uint8", "byte", "char"):
                self.emit(f"buf[pos:pos + {nbytes}] = {array}")
            else:
                self.emit("try:")
                self.emit(f"    buf[pos:pos + {nbytes}] = _mv({array}).cast('B')")
                self.emit("except TypeError:")
                self.emit(f"    buf[pos:pos + {nbytes}] = {array}.tobytes()")
            self.emit(f"pos += {nbytes}")
        else:
            dtype = self.gen.constant("_D", np.dtype(_DTYPES[base]))
            wname = self.gen.constant("_W", where)
            self.emit(f"if pos + {nbytes} > end: raise _short({wname}, pos, {nbytes}, end)")
            self.gen.views = True
            self.emit(f"{target} = _frombuffer(buf, {dtype}, {count}, pos)")
            self.emit(f"pos += {nbytes}")
        if static is not None:
            self.known = min(self.known, _lowbit(static * size))

    def fixed_array(self, sub: Any, length: int, target: str, where: str) -> None:
        if sub[0] == Nodetype.BASE and sub[1][0] in _FORMATS:
            size = _FORMATS[sub[1][0]][1]
            if size > self.known:
                self.align(size)
            else:
                pad = 0 if self.ros1 else -self.run_length % size
                self.run_format += "x" * pad
                self.run_length += pad
                self.flush()
            self.primitive_block(sub[1][0], str(length), length, target, where)
            return
        self.items(sub, str(length), target, where)

    def sequence(self, sub: Any, bound: int, target: str, where: str) -> None:
        count = self.gen.unique("n")
        primitive = sub[0] == Nodetype.BASE and sub[1][0] in _FORMATS
        lean = self.gen.lean and primitive and not self.item
        if self.mode == "decode":
            self.primitive("I", 4, count, where)
            self.flush()
            if bound:
                self.emit(f"if {count} > {bound}: raise _sequence({self.gen.constant('_W', where)}, pos - 4, "
                          f"{count}, {bound})")
        else:
            self.emit(f"{count} = 0" if lean else f"{count} = len({target})")
            self.primitive("I", 4, count, where)
            self.flush()
        if lean:
            return
        if primitive:
            size = _FORMATS[sub[1][0]][1]
            self.align(size, condition=count)
            self.primitive_block(sub[1][0], count, None, target, where)
            self.known = min(4, size)
            return
        self.items(sub, count, target, where)

    def items(self, sub: Any, count: str, target: str, where: str) -> None:
        """Strings or messages, one at a time (each aligns itself)."""
        self.flush()
        gen = self.gen
        is_string = sub[0] == Nodetype.BASE
        if is_string and sub[1][0] != "string":
            raise UnsupportedType(f"{where}: {sub[1][0]}")
        if self.mode == "decode":
            values = gen.unique("l")
            self.emit(f"{values} = []")
            self.emit(f"for _ in range({count}):")
            if is_string:
                length = gen.unique("n")
                wname = gen.constant("_W", where)
                if not self.ros1:
                    self.emit("    pos = (pos + 3) & -4")
                self.emit(f"    if pos + 4 > end: raise _short({wname}, pos, 4, end)")
                self.emit(f"    {length}, = _U32.unpack_from(buf, pos)")
                ros1 = ", False" if self.ros1 else ""
                self.emit(f"    {values}.append(_string(buf, pos + 4, {length}, end, {wname}{ros1}))")
                self.emit(f"    pos += 4 + {length}")
            else:
                function = gen.function(sub[1], item=True)
                self.emit(f"    item, pos = {function}(buf, pos, end)")
                self.emit(f"    {values}.append(item)")
            self.emit(f"{target} = _FrozenList({values})")
        else:
            self.emit(f"for item in {target}:")
            if is_string:
                nul = 0 if self.ros1 else 1
                self.emit("    s = item.encode()")
                self.emit("    k = len(s)")
                if not self.ros1:
                    if self.mode == "encode":
                        self.emit("    buf[pos:pos + 4] = _Z4")
                    self.emit("    pos = (pos + 3) & -4")
                if self.mode == "encode":
                    self.emit(f"    _U32.pack_into(buf, pos, {'k + 1' if nul else 'k'})")
                    self.emit("    buf[pos + 4:pos + 4 + k] = s")
                    if nul:
                        self.emit("    buf[pos + 4 + k] = 0")
                self.emit(f"    pos += {4 + nul} + k")
            else:
                function = gen.function(sub[1], item=True)
                call = f"{function}(item, pos)" if self.mode == "size" else f"{function}(item, buf, pos)"
                self.emit(f"    pos = {call}")
        self.known = 1


def _namespace() -> dict[str, Any]:
    return {
        "_new": object.__new__, "_short": _short, "_string": _string, "_sequence": _sequence,
        "_frombuffer": np.frombuffer, "_mv": memoryview, "_FrozenList": FrozenList,
        "_U32": struct.Struct("<I"), "_Z2": bytes(2), "_Z4": bytes(4), "_Z8": bytes(8),
    }


def _generate(types: TypeRegistry, typename: str, mode: str, lean: bool, ros1: bool = False) -> Callable[..., Any]:
    return _generate_with_views(types, typename, mode, lean, ros1)[0]


def _generate_with_views(types: TypeRegistry, typename: str, mode: str, lean: bool,
                         ros1: bool = False) -> tuple[Callable[..., Any], bool]:
    """The function, and whether it makes views on the buffer (decode only)."""
    namespace = _namespace()
    gen = _Generator(types, mode, lean, namespace, ros1)
    root = gen.function(typename, item=False)
    source = "\n\n".join(gen.functions.values())
    wire = "ros1" if ros1 else "cdr"
    exec(compile(source, f"<hetros {wire} {mode}{' lean' if lean else ''} {typename}>", "exec"), namespace)
    function: Callable[..., Any] = namespace[root]
    return function, gen.views


@dataclass(frozen=True)
class Ros1Codec:
    """ROS 1 bytes of a type whose ROS 1 definition is its own (``Ros1Type.direct``).

    ``encode(message, buffer, pos=0)`` writes ``size(message)`` bytes; ``decode(buffer,
    pos=0, end=len(buffer))`` returns a read-only message whose primitive arrays are views
    on ``buffer``. Generated like the CDR codec; rosbags' ROS 1 serializer is the reference.
    """

    typename: str
    size: Size
    encode: Encode
    decode: Decode
    compiled: bool = False


def build_ros1_codec(types: TypeRegistry, typename: str) -> Ros1Codec | None:
    """The generated ROS 1 codec of ``typename``; None where the generator has no code for it."""
    if sys.byteorder != "little":
        return None
    try:
        codec = Ros1Codec(typename, size=_generate(types, typename, "size", False, ros1=True),
                          encode=_generate(types, typename, "encode", False, ros1=True),
                          decode=_generate(types, typename, "decode", False, ros1=True))
    except UnsupportedType:
        return None
    if types.compiled:
        try:
            fast = compiled.compile_codec(types, typename, True, codec.size, codec.encode, codec.decode)
        except compiled.NotCompilable:
            return codec
        return Ros1Codec(typename, fast.size, fast.encode, fast.decode, compiled=True)
    return codec


def build_codec(types: TypeRegistry, typename: str) -> CdrCodec:
    """The fastest codec for ``typename``: generated, or rosbags' where the generator has no code."""
    if sys.byteorder == "little":
        try:
            decode, views = _generate_with_views(types, typename, "decode", False)
            codec = CdrCodec(
                typename,
                size=_generate(types, typename, "size", False),
                encode=_generate(types, typename, "encode", False),
                size_lean=_generate(types, typename, "size", True),
                encode_lean=_generate(types, typename, "encode", True),
                decode=decode,
                generated=True,
                decode_copies=not views,
            )
        except UnsupportedType:
            return reference_codec(types, typename)
        return compile_cdr(types, codec) if types.compiled else codec
    return reference_codec(types, typename)


def compile_cdr(types: TypeRegistry, codec: CdrCodec) -> CdrCodec:
    """``codec`` with the compiled interpreter in front of its generated functions (itself when
    the interpreter has no op for one of the type's fields)."""
    try:
        fast = compiled.compile_codec(types, codec.typename, False, codec.size, codec.encode, codec.decode,
                                      codec.size_lean, codec.encode_lean)
    except compiled.NotCompilable:
        return codec
    return CdrCodec(codec.typename, fast.size, fast.encode, fast.size_lean, fast.encode_lean, fast.decode,
                    generated=True, decode_copies=codec.decode_copies, compiled=True)


def reference_codec(types: TypeRegistry, typename: str) -> CdrCodec:
    """rosbags' codec behind the same interface: the reference the generated ones are checked against."""
    msgdef = types.store.get_msgdef(typename)
    store = types.store
    variable = [field.path for field in array_fields(types, typename) if field.length is None]

    def size(message: Any) -> int:
        return int(msgdef.getsize_cdr(0, message, store))

    def encode(message: Any, buffer: memoryview, pos: int = 0) -> int:
        end = pos + size(message)
        buffer[pos:end] = bytes(end - pos)
        return int(msgdef.serialize_cdr_le(buffer, pos, message, store))

    def lean(message: Any) -> Any:
        clone = copy(message)
        for path in variable:
            set_path(clone, path, get_path(clone, path)[:0])
        return clone

    def decode(buffer: memoryview, pos: int = 0, end: int = -1) -> Any:
        if end >= 0:
            buffer = buffer[:end]
        try:
            message, _end = msgdef.deserialize_cdr_le(buffer, pos, msgdef.cls, store)
        except Exception as exc:  # rosbags raises several kinds for bad bytes
            raise SerializationError(f"{len(buffer)} bytes do not decode as {typename}: {exc}") from exc
        return freeze(message)  # type: ignore[arg-type]

    return CdrCodec(typename, size, encode, lambda m: size(lean(m)), lambda m, b, p=0: encode(lean(m), b, p),
                    decode, generated=False)
