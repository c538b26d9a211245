"""A message's fields named as its bytes stream by: the authoring kit's field walker, generated per type.

A hardware node on any message type needs to know which field each byte of the CDR body is,
and CDR's alignment moves the fields once a string or a sequence has gone by. ``walk_steps``
generates, from the type's definition (as the TCPROS programs are), the steps that say it:
padding, a field's bytes, a string or a sequence (a uint32 length, then the bytes). The
:class:`FieldWalker` runs them a byte a cycle between ``cdr_in`` and ``cdr_out``: every byte
passes through with its field (an index into ``fields``), its place in the field and whether
it is a length word; a node that drives ``replace`` in that cycle sends ``replacement`` in its
place. A filter on one field is then a comparison with ``field_index(name)`` and the value to
send: the walk is the walker's.

:func:`label_bytes` is the slow reference in Python; the tests hold the walker to it and to
bytes annotated by hand.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from amaranth import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out
from rosbags.interfaces import Nodetype

from ..._errors import HardwareError
from ...msg import TypeRegistry
from ..streams._axi import axi_stream
from ..streams._bytes import bytes_in, bytes_out

StepKind = Literal["pad", "align", "bytes", "string", "sequence"]
_KINDS: tuple[StepKind, ...] = ("pad", "align", "bytes", "string", "sequence")
PRIMITIVE_SIZES = {"bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2, "int32": 4,
                   "uint32": 4, "int64": 8, "uint64": 8, "float32": 4, "float64": 8}
MAX_STEPS = 1024
PADDING = "(padding)"  # the field of alignment bytes and of bytes past the message's last field


@dataclass(frozen=True)
class Step:
    """One step of a walk: ``pad`` ``size`` bytes, ``align`` to ``size``, a field's ``size`` ``bytes``, a
    ``string`` (its length, then the bytes, NUL included) or a ``sequence`` of ``size``-byte elements."""

    kind: StepKind
    size: int
    field: int  # index into the walk's fields (0, PADDING, for pad and align)


@dataclass(frozen=True)
class Walk:
    """The fields of ``typename`` in CDR order (``fields[0]`` is :data:`PADDING`) and the steps over them."""

    typename: str
    fields: tuple[str, ...]
    steps: tuple[Step, ...]

    def field_index(self, name: str) -> int:
        if name not in self.fields:
            listed = ", ".join(self.fields[1:])
            raise HardwareError(f"{self.typename} has no field {name!r} a walker names; its fields are: {listed}")
        return self.fields.index(name)


class CdrOffset:
    """Where a walk over a type is in its CDR body, modulo 8, while that is known at generation: after a
    string or a sequence it is known only at run time, and again after an 8-byte alignment."""

    def __init__(self) -> None:
        self.known: int | None = 0

    def align(self, size: int) -> tuple[Literal["pad", "align"], int] | None:
        """What aligning to ``size`` takes: ``("pad", n)`` bytes known now, ``("align", size)`` at run
        time, or nothing."""
        if size == 1:
            return None
        if self.known is None:
            self.known = 0 if size == 8 else None
            return "align", size
        pad = -self.known % size
        self.known = (self.known + pad) % 8
        return ("pad", pad) if pad else None

    def advance(self, size: int) -> None:
        if self.known is not None:
            self.known = (self.known + size) % 8

    def lose(self) -> None:
        """A string or a sequence went by: the offset is known only at run time."""
        self.known = None


class _Builder:
    def __init__(self, typename: str) -> None:
        self.typename = typename
        self.fields: list[str] = [PADDING]
        self.steps: list[Step] = []
        self.offset = CdrOffset()

    def add(self, kind: StepKind, size: int, field: str = PADDING) -> None:
        if len(self.steps) >= MAX_STEPS:
            raise HardwareError(f"{self.typename} needs more than {MAX_STEPS} steps to walk in hardware (a large "
                                "fixed array of messages?)")
        if field not in self.fields:
            self.fields.append(field)
        self.steps.append(Step(kind, size, self.fields.index(field)))

    def align(self, size: int) -> None:
        if (step := self.offset.align(size)) is not None:
            self.add(*step)


def walk_steps(types: TypeRegistry, typename: str) -> Walk:
    """The walk of ``typename``'s CDR body; HardwareError naming the field a walker cannot name bytes in
    (a sequence of strings or of messages)."""
    builder = _Builder(typename)
    _message(types, typename, "", builder)
    return Walk(typename, tuple(builder.fields), tuple(builder.steps))


def _message(types: TypeRegistry, typename: str, prefix: str, builder: _Builder) -> None:
    for name, desc in types.fielddefs[typename][1]:
        _field(types, desc, f"{prefix}{name}", builder)


def _field(types: TypeRegistry, desc: Any, path: str, builder: _Builder) -> None:
    kind, arg = desc
    if kind == Nodetype.NAME:
        _message(types, arg, f"{path}.", builder)
        return
    if kind == Nodetype.BASE:
        if arg[0] == "string":
            builder.align(4)
            builder.add("string", 0, path)
            builder.offset.lose()
            return
        size = PRIMITIVE_SIZES[arg[0]]
        builder.align(size)
        builder.add("bytes", size, path)
        builder.offset.advance(size)
        return
    element, count = arg
    if element[0] == Nodetype.BASE and element[1][0] != "string":
        size = PRIMITIVE_SIZES[element[1][0]]
        builder.align(size if kind == Nodetype.ARRAY else 4)
        if kind == Nodetype.ARRAY:
            builder.add("bytes", size * count, path)
            builder.offset.advance(size * count)
        else:
            builder.add("sequence", size, path)
            builder.offset.lose()
        return
    if kind == Nodetype.ARRAY:
        for index in range(count):
            _field(types, element, f"{path}[{index}]", builder)
        return
    what = "strings" if element[0] == Nodetype.BASE else f"messages ({element[1]})"
    raise HardwareError(f"{path} is a sequence of {what}: the field walker names the bytes of sequences of numbers "
                        "only; walk this type in software")


@dataclass(frozen=True)
class Label:
    """What the walker says of one byte: its field's name, its place in the field (0 for padding), whether it
    is a length's."""

    field: str
    index: int
    length: bool


def label_bytes(walk: Walk, body: bytes | memoryview) -> list[Label]:
    """The slow reference: the label of every byte of ``body`` (a CDR body of ``walk.typename``)."""
    data = bytes(body)
    labels: list[Label] = []
    at = 0

    def emit(field: int, count: int, length: bool = False) -> None:
        nonlocal at
        for index in range(count):
            if at < len(data):
                labels.append(Label(walk.fields[field], index if field else 0, length))
            at += 1

    for step in walk.steps:
        if step.kind == "pad":
            emit(0, step.size)
        elif step.kind == "align":
            emit(0, -at % step.size)
        elif step.kind == "bytes":
            emit(step.field, step.size)
        else:
            value = int.from_bytes(data[at:at + 4], "little") if at + 4 <= len(data) else 0
            emit(step.field, 4, length=True)
            if step.kind == "sequence" and value:
                emit(0, -at % step.size)
            emit(step.field, value * max(step.size, 1))
    emit(0, len(data) - at)
    return labels


class FieldWalker(wiring.Component):
    """``typename``'s CDR bodies from ``cdr_in`` to ``cdr_out``, a byte a cycle, each byte named as it goes
    by (see the module). Drive ``replace`` (with ``replacement``) in a cycle ``valid`` is high to send
    another byte in its place. ``malformed`` is high with a byte that does not fit the type: the last
    byte of a message that ends before its fields do, or a byte past its last field (such bytes go
    through, named padding)."""

    def __init__(self, typename: str, data_width: int = 64, types: TypeRegistry | None = None) -> None:
        if types is None:
            from ...msg import registry
            types = registry()
        try:
            self.walk = walk_steps(types, typename)
        except HardwareError:
            self._MustUse__silence = True  # refused: nothing to warn about
            raise
        self.data_width = data_width
        super().__init__({
            "cdr_in": In(axi_stream(data_width)), "cdr_out": Out(axi_stream(data_width)),
            "valid": Out(1), "byte": Out(8), "field": Out(range(len(self.walk.fields))), "index": Out(32),
            "length": Out(1), "replace": In(1), "replacement": In(8), "malformed": Out(1)})

    @property
    def fields(self) -> tuple[str, ...]:
        return self.walk.fields

    def field_index(self, name: str) -> int:
        """The value ``field`` has while the bytes of ``name`` (``"data"``, ``"header.frame_id"``) go by."""
        return self.walk.field_index(name)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        source = bytes_in(m, self.cdr_in, self.data_width)
        sink = bytes_out(m, self.cdr_out, self.data_width)
        steps = self.walk.steps
        pc = Signal(range(len(steps) + 1))
        kind = Signal(range(len(_KINDS)))
        size = Signal(range(max(8, *(step.size for step in steps)) + 1) if steps else range(9))
        field = Signal(range(len(self.walk.fields)))
        with m.Switch(pc):
            for at, step in enumerate(steps):
                with m.Case(at):
                    m.d.comb += [kind.eq(_KINDS.index(step.kind)), size.eq(step.size), field.eq(step.field)]
        code = {name: kind == _KINDS.index(name) for name in _KINDS}
        loaded = Signal()  # the step's count is set
        count = Signal(40)  # bytes left in this part of the step
        part = Signal(2)  # string/sequence: 0 the length, 1 alignment, 2 the bytes
        word = Signal(32)
        index = Signal(32)
        position = Signal(3)  # the CDR offset mod 8
        mask = Mux(size == 8, 7, Mux(size == 4, 3, Mux(size == 2, 1, 0)))
        done = pc == len(steps)
        moves = source.valid & sink.ready
        byte_here = Signal()  # this cycle's byte belongs to the step (else the step ends without one)
        padding = Signal()
        m.d.comb += [sink.byte.eq(Mux(self.replace, self.replacement, source.byte)), sink.last.eq(source.last),
                     self.byte.eq(source.byte), self.index.eq(Mux(padding, 0, index)),
                     self.field.eq(Mux(padding, 0, field)),
                     self.length.eq((code["string"] | code["sequence"]) & (part == 0))]
        pass_byte = byte_here | done  # bytes past the last field go through as padding
        m.d.comb += [sink.valid.eq(source.valid & pass_byte), source.take.eq(moves & pass_byte),
                     self.valid.eq(moves & pass_byte)]
        with m.If(done):
            m.d.comb += padding.eq(1)
        next_step = Signal()
        finishing = Signal()  # this cycle's byte is the last the type's fields have
        last_step = pc == len(steps) - 1
        with m.If(~done):
            with m.If(~loaded):
                m.d.sync += [loaded.eq(1), part.eq(0), count.eq(Mux(code["string"] | code["sequence"], 4, size))]
            with m.Elif(code["pad"] | code["bytes"]):
                m.d.comb += [byte_here.eq(1), padding.eq(code["pad"])]
                m.d.comb += finishing.eq(last_step & (count == 1))
                with m.If(moves):
                    m.d.sync += [count.eq(count - 1), index.eq(index + 1)]
                    with m.If(count == 1):
                        m.d.comb += next_step.eq(1)
            with m.Elif(code["align"]):
                with m.If((position & mask) == 0):
                    m.d.comb += next_step.eq(1)
                with m.Else():
                    m.d.comb += [byte_here.eq(1), padding.eq(1)]
            with m.Else():  # string, sequence
                with m.Switch(part):
                    with m.Case(0):
                        m.d.comb += byte_here.eq(1)
                        with m.If(moves):
                            value = Signal(32)  # the length, little-endian, once its fourth byte is in
                            m.d.comb += [value.eq((word >> 8) | (source.byte << 24)),
                                         finishing.eq(last_step & (count == 1) & (value == 0))]
                            m.d.sync += [word.eq(value), count.eq(count - 1), index.eq(index + 1)]
                            with m.If(count == 1):
                                elements = Mux(code["sequence"], value * size, value)
                                m.d.sync += [count.eq(elements), index.eq(0),
                                             part.eq(Mux(code["sequence"] & (value != 0), 1, 2))]
                    with m.Case(1):
                        with m.If((position & mask) == 0):
                            m.d.sync += part.eq(2)
                        with m.Else():
                            m.d.comb += [byte_here.eq(1), padding.eq(1)]
                    with m.Default():
                        with m.If(count == 0):
                            m.d.comb += next_step.eq(1)
                        with m.Else():
                            m.d.comb += [byte_here.eq(1), finishing.eq(last_step & (count == 1))]
                            with m.If(moves):
                                m.d.sync += [count.eq(count - 1), index.eq(index + 1)]
                                with m.If(count == 1):
                                    m.d.comb += next_step.eq(1)
        # (last, so that they win over the steps' own updates)
        with m.If(next_step):
            m.d.sync += [pc.eq(pc + 1), loaded.eq(0), index.eq(0)]
        with m.If(moves & pass_byte):
            m.d.sync += position.eq(position + 1)
            m.d.comb += self.malformed.eq(done | (source.last & ~finishing))
            with m.If(source.last):  # the message is over: the next starts the walk again
                m.d.sync += [pc.eq(0), loaded.eq(0), index.eq(0), position.eq(0)]
        return m
