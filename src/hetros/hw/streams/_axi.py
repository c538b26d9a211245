"""The parts of a hardware topic: AXI-Stream with TLAST and TKEEP, arbiter, broadcast, FIFO.

fpgaDDS builds a topic whose endpoints all sit in hardware as an AXI-Stream network;
these are its parts, as small Amaranth components. Amaranth 0.5's ``lib.stream`` has no
TLAST, so the signature is defined here, with AXI4-Stream's names. Rules every part keeps
(the AXI4-Stream handshake): a beat moves when TVALID and TREADY are both high at a clock
edge; once TVALID is high, TVALID and TDATA hold until that happens.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from amaranth import Cat, Module, Mux, Signal
from amaranth.lib import fifo, wiring
from amaranth.lib.wiring import In, Out

from ..._errors import HardwareError


def axi_stream(data_width: int) -> wiring.Signature:
    """An AXI4-Stream from the source's side: TDATA, TKEEP (one bit per byte), TLAST, TVALID out; TREADY in."""
    if data_width < 8 or data_width % 8:
        raise HardwareError(f"data_width must be a positive multiple of 8 bits, not {data_width!r}")
    return wiring.Signature({
        "tdata": Out(data_width),
        "tkeep": Out(data_width // 8),
        "tlast": Out(1),
        "tvalid": Out(1),
        "tready": In(1),
    })


def _payload(stream: wiring.PureInterface) -> list[Signal]:
    return [stream.tdata, stream.tkeep, stream.tlast]


@dataclass(frozen=True)
class SkidInput:
    """The pipeline's side of a skid buffer: ``push`` a beat (``data``, ``keep``, ``last``) in a cycle
    only while ``room`` (a register) is high."""

    push: Signal
    data: Signal
    keep: Signal
    last: Signal
    room: Signal


def skid_buffer(m: Module, sink: Any, data_width: int) -> SkidInput:
    """Two beats in front of ``sink`` (an ``Out(axi_stream)`` port, seen from inside), so that the
    sink's TREADY reaches no register of the pipeline behind it: a node ending in one meets its
    clock on its own, whatever it is connected to."""
    lanes = data_width // 8
    out_valid, out_data, out_keep, out_last = Signal(), Signal(data_width), Signal(lanes), Signal()
    extra_valid, extra_data, extra_keep, extra_last = Signal(), Signal(data_width), Signal(lanes), Signal()
    given = SkidInput(Signal(name="push"), Signal(data_width, name="push_data"), Signal(lanes, name="push_keep"),
                      Signal(name="push_last"), Signal(name="room"))
    m.d.comb += [sink.tvalid.eq(out_valid), sink.tdata.eq(out_data), sink.tkeep.eq(out_keep),
                 sink.tlast.eq(out_last), given.room.eq(~extra_valid)]
    with m.If(~out_valid | sink.tready):
        with m.If(extra_valid):
            m.d.sync += [out_valid.eq(1), out_data.eq(extra_data), out_keep.eq(extra_keep), out_last.eq(extra_last),
                         extra_valid.eq(0)]
        with m.Else():
            m.d.sync += [out_valid.eq(given.push), out_data.eq(given.data), out_keep.eq(given.keep),
                         out_last.eq(given.last)]
    with m.Elif(given.push):
        m.d.sync += [extra_valid.eq(1), extra_data.eq(given.data), extra_keep.eq(given.keep),
                     extra_last.eq(given.last)]
    return given


def register_slice(m: Module, source: Any, data_width: int) -> wiring.PureInterface:
    """``source`` (an ``In(axi_stream)`` port, seen from inside) behind a skid buffer of two beats: the
    stream the node reads instead, while ``source``'s TREADY is a register. A node whose input starts
    with one never makes its publisher's timing depend on its own decisions (with a skid buffer at each
    output too, every node-to-node path in a target starts and ends at a register)."""
    inner = axi_stream(data_width).create(path=("slice",))
    given = skid_buffer(m, inner, data_width)
    m.d.comb += [given.push.eq(source.tvalid & given.room), given.data.eq(source.tdata), given.keep.eq(source.tkeep),
                 given.last.eq(source.tlast), source.tready.eq(given.room)]
    return inner


class RoundRobinArbiter(wiring.Component):
    """N publishers onto one stream, a whole message at a time.

    The grant moves on only after a beat with TLAST: messages are never interleaved. While
    no message is under way the next publisher with TVALID after the last granted one is
    shown, with no idle cycle; if the sink stalls it, the choice is locked so TVALID and
    TDATA hold.
    """

    def __init__(self, inputs: int, data_width: int) -> None:
        if inputs < 2:
            self._MustUse__silence = True  # refused: nothing to warn about
            raise HardwareError(f"an arbiter needs at least 2 inputs, not {inputs!r}")
        self.inputs = inputs
        members = {f"s{i}": In(axi_stream(data_width)) for i in range(inputs)}
        super().__init__({**members, "m": Out(axi_stream(data_width))})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        sources = [getattr(self, f"s{i}") for i in range(self.inputs)]
        grant = Signal(range(self.inputs), init=self.inputs - 1)  # so publisher 0 goes first
        locked = Signal()
        pick = Signal(range(self.inputs))
        with m.Switch(grant):
            for last in range(self.inputs):
                with m.Case(last):
                    order = [(last + 1 + k) % self.inputs for k in range(self.inputs)]
                    m.d.comb += pick.eq(last)
                    for index in reversed(order):  # the last assignment wins: the first in order
                        with m.If(sources[index].tvalid):
                            m.d.comb += pick.eq(index)
        chosen = Signal(range(self.inputs))
        m.d.comb += chosen.eq(Mux(locked, grant, pick))
        with m.Switch(chosen):
            for index, source in enumerate(sources):
                with m.Case(index):
                    m.d.comb += [Cat(*_payload(self.m)).eq(Cat(*_payload(source))),
                                 self.m.tvalid.eq(source.tvalid), source.tready.eq(self.m.tready)]
        with m.If(self.m.tvalid):
            m.d.sync += grant.eq(chosen)
            m.d.sync += locked.eq(~(self.m.tready & self.m.tlast))
        return m


class Broadcast(wiring.Component):
    """One stream to N subscribers; a beat is retired only when every subscriber has taken it."""

    def __init__(self, outputs: int, data_width: int) -> None:
        if outputs < 2:
            self._MustUse__silence = True  # refused: nothing to warn about
            raise HardwareError(f"a broadcast needs at least 2 outputs, not {outputs!r}")
        self.outputs = outputs
        members = {f"m{i}": Out(axi_stream(data_width)) for i in range(outputs)}
        super().__init__({"s": In(axi_stream(data_width)), **members})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        sinks = [getattr(self, f"m{i}") for i in range(self.outputs)]
        taken = Signal(self.outputs)
        for index, sink in enumerate(sinks):
            m.d.comb += [Cat(*_payload(sink)).eq(Cat(*_payload(self.s))),
                         sink.tvalid.eq(self.s.tvalid & ~taken[index])]
        done = Cat(*(sink.tready | taken[i] for i, sink in enumerate(sinks)))
        m.d.comb += self.s.tready.eq(done.all())
        with m.If(self.s.tvalid & self.s.tready):
            m.d.sync += taken.eq(0)
        with m.Else():
            for index, sink in enumerate(sinks):
                with m.If(sink.tvalid & sink.tready):
                    m.d.sync += taken[index].eq(1)
        return m


MIN_FIFO_DEPTH = 3  # SyncFIFOBuffered of depth 2 moves a beat every other cycle


class StreamFifo(wiring.Component):
    """A FIFO of ``depth`` beats in front of one subscriber (Amaranth's SyncFIFOBuffered)."""

    def __init__(self, depth: int, data_width: int) -> None:
        if depth < MIN_FIFO_DEPTH:
            self._MustUse__silence = True  # refused: nothing to warn about
            raise HardwareError(f"hw_fifo must be at least {MIN_FIFO_DEPTH} beats (2 runs at half rate), "
                                f"not {depth!r}")
        self.depth = depth
        self.data_width = data_width
        super().__init__({"s": In(axi_stream(data_width)), "m": Out(axi_stream(data_width))})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        width = len(Cat(*_payload(self.s)))
        m.submodules.buffer = buffer = fifo.SyncFIFOBuffered(width=width, depth=self.depth)
        m.d.comb += [
            buffer.w_data.eq(Cat(*_payload(self.s))),
            buffer.w_en.eq(self.s.tvalid),
            self.s.tready.eq(buffer.w_rdy),
            Cat(*_payload(self.m)).eq(buffer.r_data),
            self.m.tvalid.eq(buffer.r_rdy),
            buffer.r_en.eq(self.m.tready),
        ]
        return m


class TopicNetwork(wiring.Component):
    """One hardware topic: ``pub<i>`` streams in, ``sub<j>`` streams out.

    1 publisher to 1 subscriber is wiring only; more publishers add an arbiter, more
    subscribers a broadcast, and ``fifo_depth`` a FIFO in front of every subscriber.
    """

    def __init__(self, publishers: int, subscribers: int, data_width: int, fifo_depth: int | None = None) -> None:
        if publishers < 1 or subscribers < 1:
            self._MustUse__silence = True  # refused: nothing to warn about
            raise HardwareError(f"a hardware topic needs a publisher and a subscriber, not {publishers} and "
                                f"{subscribers}")
        self.publishers = publishers
        self.subscribers = subscribers
        self.data_width = data_width
        self.fifo_depth = fifo_depth
        members = {f"pub{i}": In(axi_stream(data_width)) for i in range(publishers)}
        members |= {f"sub{j}": Out(axi_stream(data_width)) for j in range(subscribers)}
        super().__init__(members)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        sources = [getattr(self, f"pub{i}") for i in range(self.publishers)]
        sinks = [getattr(self, f"sub{j}") for j in range(self.subscribers)]
        merged = sources[0]
        if self.publishers > 1:
            m.submodules.arbiter = arbiter = RoundRobinArbiter(self.publishers, self.data_width)
            for index, source in enumerate(sources):
                _link(m, source, getattr(arbiter, f"s{index}"))
            merged = arbiter.m
        fanned = [merged]
        if self.subscribers > 1:
            m.submodules.broadcast = broadcast = Broadcast(self.subscribers, self.data_width)
            _link(m, merged, broadcast.s)
            fanned = [getattr(broadcast, f"m{j}") for j in range(self.subscribers)]
        for index, (out, sink) in enumerate(zip(fanned, sinks, strict=True)):
            if self.fifo_depth:
                buffer = StreamFifo(self.fifo_depth, self.data_width)
                m.submodules[f"fifo{index}"] = buffer
                _link(m, out, buffer.s)
                out = buffer.m
            _link(m, out, sink)
        return m


def _link(m: Module, source: wiring.PureInterface, sink: wiring.PureInterface) -> None:
    """Carry ``source``'s beats to ``sink`` combinationally (either may be a port of ours or of a part)."""
    m.d.comb += [Cat(*_payload(sink)).eq(Cat(*_payload(source))), sink.tvalid.eq(source.tvalid),
                 source.tready.eq(sink.tready)]


__all__ = ["MIN_FIFO_DEPTH", "Broadcast", "RoundRobinArbiter", "StreamFifo", "TopicNetwork", "axi_stream"]
