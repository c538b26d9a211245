"""Hardware TCPROS (Sugata et al.): the data phase of a ROS 1 topic framed by the fpga target itself.

A hardware topic carries CDR bodies (``_beats``); a ROS 1 subscriber reads TCPROS frames: a
4-byte little-endian length, then ROS 1's serialization, which has no alignment padding, no NUL
after a string, and fields CDR lacks (``std_msgs/Header``'s ``seq``). A *program*, generated
per type from both definitions, says byte by byte how one becomes the other; two small engines
run it: :class:`Ros1Framer` (CDR beats in, frames out, for a topic the hardware publishes to
ROS 1) and :class:`Ros1Deframer` (frames in, CDR beats out, for one it subscribes). Software
does only the registration phase and moves the frames' bytes unchanged (``launch._gateway``).

:func:`run_program` is the program's slow reference in Python; the tests hold both engines and
it to rosbags' ROS 1 serialization of the same message.

The engines move a byte a cycle. A frame's length comes before its bytes: for a type whose ROS 1
size is fixed the framer knows it at elaboration and streams; otherwise it is known once the
length of the type's last string or sequence has been read (every field after it is of fixed
size), so the framer holds only the ROS 1 bytes before that field (``max_frame`` bytes of block
RAM at most: an ``Image``'s header, not its pixels), sends the length and them, and streams the
rest.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from amaranth import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from rosbags.interfaces import Nodetype

from ..._errors import HardwareError
from ...msg import TypeRegistry, ros1_store
from ..streams._axi import axi_stream
from ..streams._bytes import ByteSource, bytes_in, bytes_out
from ._walker import PRIMITIVE_SIZES, CdrOffset

# what one step of a program does with the CDR side (C) and the ROS 1 side (R)
OpKind = Literal[
    "pad",       # n padding bytes of C (known at generation)
    "align",     # C's padding up to a multiple of n (known only at run time)
    "copy",      # n bytes the same on both sides
    "ros1",      # n zero bytes only R has (Header.seq)
    "cdr",       # n bytes only C has (an empty message's placeholder)
    "string",    # a uint32 length and the bytes: C counts and sends a NUL, R neither
    "sequence",  # a uint32 count, then count elements of n bytes (C aligns them to n if count > 0)
]
_KINDS: tuple[OpKind, ...] = ("pad", "align", "copy", "ros1", "cdr", "string", "sequence")
# a program longer than this (a large fixed array of messages, unrolled) is refused
MAX_STEPS = 1024
_PLACEHOLDER = "structure_needs_at_least_one_member"


@dataclass(frozen=True)
class Op:
    kind: OpKind
    size: int = 0
    field: str = ""  # the field it comes from, for errors and ``describe``


@dataclass(frozen=True)
class Ros1Program:
    """How ``typename``'s CDR body and its ROS 1 serialization map onto each other, step by step."""

    typename: str
    ops: tuple[Op, ...]

    @property
    def fixed_ros1_size(self) -> int | None:
        """ROS 1 bytes of every message, when no step's size depends on the message."""
        if any(op.kind in ("string", "sequence") for op in self.ops):
            return None
        return sum(op.size for op in self.ops if op.kind in ("copy", "ros1"))

    @property
    def length_known_at(self) -> tuple[int, int] | None:
        """For a type of variable size, where its frame's length becomes known: the step of its last
        string or sequence (once that step's length is read, every ROS 1 byte still to come is counted)
        and the ROS 1 bytes of the fixed steps after it. None for a fixed size."""
        variable = [index for index, op in enumerate(self.ops) if op.kind in ("string", "sequence")]
        if not variable:
            return None
        return variable[-1], sum(op.size for op in self.ops[variable[-1] + 1:] if op.kind in ("copy", "ros1"))

    def describe(self) -> str:
        return "\n".join(f"{op.kind:<9} {op.size:>5}  {op.field}" for op in self.ops)


class _Walk:
    """Generation state: the steps so far and where the CDR side is."""

    def __init__(self, typename: str) -> None:
        self.typename = typename
        self.ops: list[Op] = []
        self.offset = CdrOffset()

    def add(self, kind: OpKind, size: int, field: str) -> None:
        if len(self.ops) >= MAX_STEPS:
            raise HardwareError(f"{self.typename} needs more than {MAX_STEPS} steps to frame in hardware (a large "
                                "fixed array of messages?); frame it in software: leave the topic to the ROS 1 bridge")
        previous = self.ops[-1] if self.ops else None
        if previous is not None and previous.kind == kind and kind in ("copy", "pad", "ros1", "cdr"):
            self.ops[-1] = Op(kind, previous.size + size, previous.field)  # one step for a run of fields
        else:
            self.ops.append(Op(kind, size, field))

    def align(self, size: int, field: str) -> None:
        if (step := self.offset.align(size)) is not None:
            self.add(step[0], step[1], field)


def ros1_program(types: TypeRegistry, typename: str) -> Ros1Program:
    """The program of ``typename`` (see the module's docstring); HardwareError for what hardware cannot frame."""
    if typename not in ros1_store().fielddefs:
        raise HardwareError(f"{typename} has no ROS 1 definition (rosbags' ROS 1 Noetic store lacks it): a topic of "
                            "this type cannot be framed for ROS 1")
    walk = _Walk(typename)
    _message(types, ros1_store(), typename, typename, walk)
    if not walk.ops:
        raise HardwareError(f"{typename} has no bytes on either side; nothing to frame")
    return Ros1Program(typename, tuple(walk.ops))


def _message(types: TypeRegistry, store: Any, typename: str, where: str, walk: _Walk) -> None:
    ros2 = list(types.fielddefs[typename][1])
    ros1 = {name: desc for name, desc in store.fielddefs[typename][1] if name != _PLACEHOLDER}
    lower = {name.lower(): name for name in ros1}
    common = [name for name, _ in ros2 if name != _PLACEHOLDER]
    matched = [name if name in ros1 else lower.get(name.lower(), "") for name in common]
    if "" in matched:
        missing = common[matched.index("")]
        raise HardwareError(f"{where}: {typename}'s field {missing!r} has no ROS 1 counterpart; it cannot be framed "
                            "for ROS 1")
    if [n for n in ros1 if n in matched] != matched:
        raise HardwareError(f"{where}: ROS 1 orders the fields of {typename} differently from ROS 2; frame it in "
                            "software (leave the topic to the ROS 1 bridge)")
    ros2_by_ros1 = {m: desc for m, (name, desc) in zip(matched, [f for f in ros2 if f[0] != _PLACEHOLDER],
                                                        strict=True)}
    if any(name == _PLACEHOLDER for name, _ in ros2):
        walk.add("cdr", 1, f"{where}.{_PLACEHOLDER}")
        walk.offset.advance(1)
    for name, desc in ros1.items():
        path = f"{where}.{name}"
        if name in ros2_by_ros1:
            _field(types, store, ros2_by_ros1[name], path, walk)
        else:
            walk.add("ros1", _ros1_only_size(store, desc, path), path)


def _ros1_only_size(store: Any, desc: Any, path: str) -> int:
    """ROS 1 bytes of an all-zero value of a field CDR lacks (``seq``; an empty string or sequence is its
    4-byte zero count)."""
    kind, arg = desc
    if kind == Nodetype.BASE:
        return 4 if arg[0] == "string" else PRIMITIVE_SIZES[arg[0]]
    if kind == Nodetype.NAME:
        return sum(_ros1_only_size(store, sub, f"{path}.{n}") for n, sub in store.fielddefs[arg][1])
    if kind == Nodetype.SEQUENCE:
        return 4
    sub, count = arg
    return int(count) * _ros1_only_size(store, sub, path)


def _field(types: TypeRegistry, store: Any, desc: Any, path: str, walk: _Walk) -> None:
    kind, arg = desc
    if kind == Nodetype.NAME:
        _message(types, store, arg, path, walk)
        return
    if kind == Nodetype.BASE:
        if arg[0] == "string":
            walk.align(4, path)
            walk.add("string", 0, path)
            walk.offset.lose()
            return
        size = PRIMITIVE_SIZES[arg[0]]
        walk.align(size, path)
        walk.add("copy", size, path)
        walk.offset.advance(size)
        return
    element, count = arg
    if element[0] == Nodetype.BASE and element[1][0] != "string":
        size = PRIMITIVE_SIZES[element[1][0]]
        if kind == Nodetype.ARRAY:
            walk.align(size, path)
            walk.add("copy", size * count, path)
            walk.offset.advance(size * count)
            return
        walk.align(4, path)
        walk.add("sequence", size, path)
        walk.offset.lose()
        return
    if kind == Nodetype.ARRAY:
        for index in range(count):
            _field(types, store, element, f"{path}[{index}]", walk)
        return
    what = "strings" if element[0] == Nodetype.BASE else f"messages ({element[1]})"
    raise HardwareError(f"{path} is a sequence of {what}: hardware TCPROS frames sequences of numbers only; "
                        "frame this topic in software (leave it to the ROS 1 bridge)")


def run_program(program: Ros1Program, data: bytes | memoryview, to_ros1: bool) -> bytes:
    """The slow reference: a CDR body to a ROS 1 frame (``to_ros1``), or a ROS 1 frame to a CDR body.
    HardwareError names the step and the offset where ``data`` does not fit the type."""
    source = bytes(data)
    out = bytearray()
    at = 0
    if not to_ros1:
        if len(source) < 4 or int.from_bytes(source[:4], "little") != len(source) - 4:
            raise HardwareError(f"a ROS 1 frame of {program.typename} starts with its length, "
                                f"{len(source) - 4}; it has {source[:4].hex()}")
        at = 4

    def take(count: int, op: Op) -> bytes:
        nonlocal at
        if at + count > len(source):
            raise HardwareError(f"{program.typename}: {op.field} ({op.kind}) needs {count} bytes at offset {at}, "
                                f"the message ends at {len(source)}")
        chunk = source[at:at + count]
        at += count
        return chunk

    def cdr_position() -> int:
        return at if to_ros1 else len(out)

    def cdr_pad(size: int, op: Op) -> None:
        if to_ros1:
            take(size, op)
        else:
            out.extend(bytes(size))

    for op in program.ops:
        if op.kind == "pad":
            cdr_pad(op.size, op)
        elif op.kind == "align":
            cdr_pad(-cdr_position() % op.size, op)
        elif op.kind == "copy":
            out.extend(take(op.size, op))
        elif op.kind == "ros1":
            out.extend(bytes(op.size)) if to_ros1 else take(op.size, op)
        elif op.kind == "cdr":
            take(op.size, op) if to_ros1 else out.extend(bytes(op.size))
        elif op.kind == "string":
            length = int.from_bytes(take(4, op), "little")
            chars = max(length - 1, 0) if to_ros1 else length
            out.extend((chars if to_ros1 else chars + 1).to_bytes(4, "little"))
            out.extend(take(chars, op))
            if to_ros1 and length:
                take(1, op)
            elif not to_ros1:
                out.append(0)
        else:
            count = int.from_bytes(take(4, op), "little")
            out.extend(count.to_bytes(4, "little"))
            if count:
                cdr_pad(-cdr_position() % op.size, op)
                out.extend(take(count * op.size, op))
    if at != len(source):
        raise HardwareError(f"{program.typename}: {len(source) - at} bytes left over at offset {at}")
    return bytes(len(out).to_bytes(4, "little") + out) if to_ros1 else bytes(out)


class _Engine:
    """A program run one byte a cycle between a byte source (``_bytes.bytes_in``) and a sink.

    ``to_ros1``: the source is a CDR body, the sink gets ROS 1 bytes (no length); else the source
    is ROS 1 bytes after the length and the sink gets a CDR body. ``start`` begins a message;
    ``running`` is high until its last step; ``malformed`` when the source's message ended before
    the program did, or went on after it (the rest is dropped). ``ended_before``: the
    source's message ended with the byte taken as ``start`` rose (a frame of only its length).
    """

    def __init__(self, m: Module, program: Ros1Program, to_ros1: bool, source: Any, start: Any,
                 ended_before: Any = 0) -> None:
        self.valid, self.byte, self.ready = Signal(), Signal(8), Signal()
        self.malformed, self.running = Signal(), Signal()
        ops = program.ops
        steps = len(ops)
        pc = Signal(range(steps + 1), init=steps)  # idle until ``start``
        self.pc = pc
        kind = Signal(range(len(_KINDS)))
        size = Signal(range(max(8, *(op.size for op in ops)) + 1))
        with m.Switch(pc):
            for index, op in enumerate(ops):
                with m.Case(index):
                    m.d.comb += [kind.eq(_KINDS.index(op.kind)), size.eq(op.size)]
        code = {k: kind == _KINDS.index(k) for k in _KINDS}
        shift = Signal(2)  # log2 of an align step's alignment or of a sequence's element size
        m.d.comb += shift.eq(Mux(size == 8, 3, Mux(size == 4, 2, Mux(size == 2, 1, 0))))
        mask = Signal(3)
        m.d.comb += mask.eq((Const(1, 4) << shift) - 1)
        loaded = Signal()
        count = Signal(32)
        phase = Signal(2)  # string/sequence: 0 read the length, 1 write it, 2 align, 3 the bytes (and NUL)
        word = Signal(32)
        out_word = Signal(32)
        nul = Signal()
        position = Signal(3)  # the CDR offset mod 8
        ended = Signal()  # the source's last byte was taken
        draining = Signal()
        take = Signal()  # the engine wants the source's byte (taken only when there is one)
        m.d.comb += source.take.eq(take & source.valid)
        moved_in = source.valid & take
        moved_out = self.valid & self.ready
        with m.If(moved_in if to_ros1 else moved_out):
            m.d.sync += position.eq(position + 1)
        with m.If(moved_in & source.last):
            m.d.sync += ended.eq(1)
        next_step = Signal()
        m.d.comb += self.running.eq((pc < steps) & ~draining)
        with m.If(start):
            m.d.sync += [pc.eq(0), loaded.eq(0), position.eq(0), ended.eq(ended_before), draining.eq(0)]
        with m.If(next_step):
            m.d.sync += [pc.eq(pc + 1), loaded.eq(0)]
            with m.If((pc == steps - 1) & ~ended & ~(moved_in & source.last)):
                m.d.comb += self.malformed.eq(1)  # the message goes on: drop the rest
                m.d.sync += draining.eq(1)
        with m.If(draining):
            m.d.comb += take.eq(1)
            with m.If(moved_in & source.last):
                m.d.sync += draining.eq(0)
        with m.If(self.running & ended & source.valid & take):
            m.d.comb += self.malformed.eq(1)  # the program wants bytes of the next message

        def cdr_padding() -> Any:
            """Skip (to ROS 1) or write (to CDR) one padding byte; what moved."""
            if to_ros1:
                m.d.comb += take.eq(1)
                return moved_in
            m.d.comb += self.valid.eq(1)
            return moved_out

        def counted(moved: Any) -> None:
            with m.If(moved):
                m.d.sync += count.eq(count - 1)
                with m.If(count == 1):
                    m.d.comb += next_step.eq(1)

        def copy() -> None:
            m.d.comb += [self.valid.eq(source.valid), self.byte.eq(source.byte), take.eq(self.ready)]

        # a string's or sequence's length has been read and its ROS 1 length is about to go out: the ROS 1
        # bytes of its characters or elements (``out_word`` counts them, elements of ``size`` bytes)
        self.length_read = Signal()
        self.variable_bytes = Signal(35)
        m.d.comb += [self.length_read.eq(self.running & loaded & (code["string"] | code["sequence"]) & (phase == 1)
                                         & (count == 4)),
                     self.variable_bytes.eq(Mux(code["string"], out_word, out_word << shift))]

        with m.If(self.running):
            with m.If(~loaded):
                m.d.sync += [count.eq(Mux(code["string"] | code["sequence"], 4, size)), loaded.eq(1), phase.eq(0)]
            with m.Elif(code["copy"]):
                copy()
                counted(moved_out)
            with m.Elif(code["pad"]):
                counted(cdr_padding())
            with m.Elif(code["align"]):
                with m.If((position & mask) == 0):
                    m.d.comb += next_step.eq(1)
                with m.Else():
                    cdr_padding()
            with m.Elif(code["ros1"] if to_ros1 else code["cdr"]):
                m.d.comb += self.valid.eq(1)
                counted(moved_out)
            with m.Elif(code["cdr"] if to_ros1 else code["ros1"]):
                m.d.comb += take.eq(1)
                counted(moved_in)
            with m.Else():  # string, sequence
                with m.Switch(phase):
                    with m.Case(0):
                        length = Cat(word[8:], source.byte)
                        m.d.comb += take.eq(1)
                        with m.If(moved_in):
                            m.d.sync += [word.eq(length), count.eq(count - 1)]
                            with m.If(count == 1):
                                if to_ros1:  # CDR counts the NUL (an empty string may be 0: no NUL then)
                                    chars = Mux(length != 0, length - 1, 0)
                                    written = Mux(code["string"], chars, length)
                                    m.d.sync += nul.eq(code["string"] & (length != 0))
                                else:
                                    written = Mux(code["string"], length + 1, length)
                                    m.d.sync += nul.eq(code["string"])
                                m.d.sync += [out_word.eq(written), phase.eq(1), count.eq(4)]
                    with m.Case(1):
                        m.d.comb += [self.valid.eq(1), self.byte.eq(out_word[:8])]
                        with m.If(moved_out):
                            m.d.sync += [out_word.eq(out_word >> 8), count.eq(count - 1)]
                            with m.If(count == 1):
                                with m.If(code["sequence"]):
                                    m.d.sync += [count.eq(word << shift), phase.eq(2)]
                                    with m.If(word == 0):
                                        m.d.comb += next_step.eq(1)
                                with m.Else():
                                    chars = (Mux(word != 0, word - 1, 0)) if to_ros1 else word
                                    m.d.sync += [count.eq(chars), phase.eq(3)]
                    with m.Case(2):
                        with m.If((position & mask) == 0):
                            m.d.sync += phase.eq(3)
                        with m.Else():
                            cdr_padding()
                    with m.Case(3):
                        with m.If(count != 0):
                            copy()
                            with m.If(moved_out):
                                m.d.sync += count.eq(count - 1)
                                with m.If((count == 1) & ~nul):
                                    m.d.comb += next_step.eq(1)
                        with m.Elif(nul):
                            if to_ros1:
                                m.d.comb += take.eq(1)
                                with m.If(moved_in):
                                    m.d.comb += next_step.eq(1)
                            else:
                                m.d.comb += self.valid.eq(1)
                                with m.If(moved_out):
                                    m.d.comb += next_step.eq(1)
                        with m.Else():
                            m.d.comb += next_step.eq(1)


def _one_byte_behind(m: Module, engine: _Engine, sink: Any) -> Any:
    """The engine's bytes to ``sink`` one byte late, so that the message's last byte, known only once the
    program has ended (trailing steps may emit nothing), carries TLAST; high as the message is out."""
    held, held_valid = Signal(8), Signal()
    m.d.comb += engine.ready.eq(~held_valid | sink.ready)
    m.d.comb += [sink.valid.eq(held_valid & (engine.valid | ~engine.running)), sink.byte.eq(held),
                 sink.last.eq(~engine.running)]
    with m.If(engine.valid & engine.ready):
        m.d.sync += [held.eq(engine.byte), held_valid.eq(1)]
    with m.Elif(sink.valid & sink.ready):
        m.d.sync += held_valid.eq(0)
    finished = Signal()
    m.d.comb += finished.eq(~engine.running & (~held_valid | sink.ready))
    with m.If(finished):
        m.d.sync += held_valid.eq(0)
    return finished


class Ros1Framer(wiring.Component):
    """CDR bodies in (``cdr``), TCPROS frames out (``frame``): the length, then ROS 1's bytes.

    ``malformed`` is high for a cycle when a message did not fit the type (the co-simulation reports it).
    """

    def __init__(self, program: Ros1Program, data_width: int, max_frame: int = 4096) -> None:
        if max_frame < 1:
            raise HardwareError(f"max_frame must be at least 1 byte, not {max_frame!r}")
        self.program, self.data_width, self.max_frame = program, data_width, max_frame
        super().__init__({"cdr": In(axi_stream(data_width)), "frame": Out(axi_stream(data_width)),
                          "malformed": Out(1)})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        source = bytes_in(m, self.cdr, self.data_width)
        sink = bytes_out(m, self.frame, self.data_width)
        fixed = self.program.fixed_ros1_size
        known_at = self.program.length_known_at
        # idle -> (prefix while streaming a fixed size) -> program -> (prefix, then stored bytes)
        state = Signal(3)  # 0 idle, 1 program (held), 2 length, 3 held bytes, 4 dropping
        start = Signal()
        engine = _Engine(m, self.program, True, source, start)
        sent = Signal(range(max(self.max_frame, 4) + 1))
        m.d.comb += self.malformed.eq(engine.malformed)
        if known_at is None or fixed is not None:
            # the length is known: it leads, then the program's bytes stream through
            fixed = fixed or 0
            prefix = Const(fixed, 32)
            with m.Switch(state):
                with m.Case(0):
                    with m.If(source.valid):
                        m.d.sync += [state.eq(2), sent.eq(0)]
                with m.Case(2):
                    m.d.comb += [sink.valid.eq(1), sink.byte.eq(prefix.word_select(sent[:2], 8)),
                                 sink.last.eq((sent == 3) & (fixed == 0))]
                    with m.If(sink.ready):
                        m.d.sync += sent.eq(sent + 1)
                        with m.If(sent == 3):
                            m.d.comb += start.eq(1)
                            m.d.sync += state.eq(1)
                with m.Case(1):
                    with m.If(_one_byte_behind(m, engine, sink)):
                        m.d.sync += state.eq(0)
            return m
        # a variable size: the ROS 1 bytes before the last string or sequence are held (``max_frame`` bytes
        # of block RAM at most) until that field's length is read; then the frame's length goes out, the
        # held bytes after it, and the rest streams
        last_variable, tail_bytes = known_at
        store = Memory(shape=unsigned(8), depth=self.max_frame, init=[])
        m.submodules.store = store
        write = store.write_port()
        read = store.read_port(domain="sync")
        stored = Signal(range(self.max_frame + 1))  # ROS 1 bytes held
        length = Signal(32)
        overflow = Signal()
        # the held bytes go out through two stages that move together: the read port (which holds its byte
        # while not enabled) and a register, so neither the block RAM's output nor the sink's ready decides
        # an address in the cycle it arrives
        fetch = Signal.like(stored)  # the next byte to read
        fetched, shown = Signal(), Signal()  # the read port holds a byte; ``shown_byte`` holds one
        shown_byte = Signal(8)
        replaying = Signal()
        m.d.comb += [write.addr.eq(stored), write.data.eq(engine.byte), read.addr.eq(fetch),
                     read.en.eq(~replaying | ~shown | sink.ready)]
        length_known = engine.length_read & (engine.pc == last_variable)
        streaming = Signal()  # the held bytes are out: the engine's go to the frame
        with m.If(streaming):
            with m.If(_one_byte_behind(m, engine, sink)):
                m.d.sync += streaming.eq(0)
        with m.Else():
            with m.Switch(state):
                with m.Case(0):
                    with m.If(source.valid):
                        m.d.comb += start.eq(1)
                        m.d.sync += [state.eq(1), stored.eq(0), overflow.eq(0)]
                with m.Case(1):
                    m.d.comb += engine.ready.eq(~length_known)
                    with m.If(engine.valid & ~length_known):
                        with m.If(stored < self.max_frame):
                            m.d.comb += write.en.eq(1)
                            m.d.sync += stored.eq(stored + 1)
                        with m.Else():
                            m.d.sync += overflow.eq(1)
                    with m.If(length_known):
                        m.d.sync += [length.eq(stored + 4 + engine.variable_bytes + tail_bytes), state.eq(2),
                                     sent.eq(0)]
                        with m.If(overflow):  # too long to hold: dropped (its bytes run out), reported
                            m.d.comb += self.malformed.eq(1)
                            m.d.sync += state.eq(4)
                    with m.If(~engine.running):  # the message ended early (the engine reported it): dropped
                        m.d.sync += state.eq(0)
                with m.Case(2):
                    m.d.comb += [sink.valid.eq(1), sink.byte.eq(length.word_select(sent[:2], 8))]
                    with m.If(sink.ready):
                        m.d.sync += sent.eq(sent + 1)
                        with m.If(sent == 3):
                            m.d.sync += [sent.eq(0), state.eq(Mux(stored == 0, 0, 3)), streaming.eq(stored == 0),
                                         fetch.eq(0), fetched.eq(0), shown.eq(0)]
                with m.Case(3):
                    m.d.comb += [replaying.eq(1), sink.valid.eq(shown), sink.byte.eq(shown_byte)]
                    with m.If(~shown | sink.ready):
                        m.d.sync += [shown.eq(fetched), shown_byte.eq(read.data), fetched.eq(fetch < stored)]
                        with m.If(fetch < stored):
                            m.d.sync += fetch.eq(fetch + 1)
                    with m.If(shown & sink.ready):
                        m.d.sync += sent.eq(sent + 1)
                        with m.If(sent == stored - 1):
                            m.d.sync += [state.eq(0), streaming.eq(1)]
                with m.Case(4):  # dropping
                    m.d.comb += engine.ready.eq(1)
                    with m.If(~engine.running):
                        m.d.sync += state.eq(0)
        return m


class Ros1Deframer(wiring.Component):
    """TCPROS frames in (``frame``: the length, then ROS 1's bytes), CDR bodies out (``cdr``)."""

    def __init__(self, program: Ros1Program, data_width: int) -> None:
        self.program, self.data_width = program, data_width
        super().__init__({"frame": In(axi_stream(data_width)), "cdr": Out(axi_stream(data_width)),
                          "malformed": Out(1)})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        source = bytes_in(m, self.frame, self.data_width)
        sink = bytes_out(m, self.cdr, self.data_width)
        state = Signal(2)  # 0 the length, 1 program
        skipped = Signal(2)
        start = Signal()
        # the length's bytes go past the engine, which starts after them
        gate = Signal()
        inner = ByteSource(source.byte, source.valid & (state == 1), source.last, gate)
        engine = _Engine(m, self.program, False, inner, start, ended_before=source.last)
        m.d.comb += self.malformed.eq(engine.malformed)
        with m.Switch(state):
            with m.Case(0):
                m.d.comb += source.take.eq(1)
                with m.If(source.valid):
                    m.d.sync += skipped.eq(skipped + 1)
                    with m.If(skipped == 3):
                        m.d.comb += start.eq(1)
                        m.d.sync += [state.eq(1), skipped.eq(0)]
            with m.Case(1):
                m.d.comb += source.take.eq(gate)
                with m.If(_one_byte_behind(m, engine, sink)):
                    m.d.sync += state.eq(0)
        return m
