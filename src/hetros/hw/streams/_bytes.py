"""A stream of beats as one byte a cycle, and back: the front and back of byte-serial hardware nodes.

A node that walks a message's fields (``_image``, ``_sort``) sees the CDR body byte by byte
and writes its output byte by byte; these two gearboxes sit between it and its AXI4-Stream
ports, at any ``data_width``, with no bubble between beats.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from amaranth import Const, Module, Signal


@dataclass(frozen=True)
class ByteSource:
    """``byte`` (valid while ``valid``) is taken when the node drives ``take`` high; ``last`` marks the
    message's last byte."""

    byte: Any
    valid: Any
    last: Any
    take: Signal


@dataclass(frozen=True)
class ByteSink:
    """The node shows ``byte`` (and ``last`` on a message's last byte) with ``valid``; it moves when
    ``ready`` is high in the same cycle."""

    valid: Signal
    byte: Signal
    last: Signal
    ready: Any


def bytes_in(m: Module, source: Any, data_width: int) -> ByteSource:
    """Beats from ``source`` (an ``In(axi_stream)`` port, seen from inside) as one byte a cycle."""
    per_beat = data_width // 8
    held = Signal(data_width)
    count = Signal(range(per_beat + 1))
    held_last = Signal()
    take = Signal()
    m.d.comb += source.tready.eq((count == 0) | ((count == 1) & take))
    with m.If(source.tvalid & source.tready):
        m.d.sync += [held.eq(source.tdata), held_last.eq(source.tlast),
                     count.eq(sum(source.tkeep[i] for i in range(per_beat)))]
    with m.Elif(take & (count != 0)):
        m.d.sync += [held.eq(held >> 8), count.eq(count - 1)]
    return ByteSource(held[:8], count != 0, held_last & (count == 1), take)


def bytes_out(m: Module, sink: Any, data_width: int) -> ByteSink:
    """Bytes packed into beats on ``sink`` (an ``Out(axi_stream)`` port, seen from inside)."""
    per_beat = data_width // 8
    packing = Signal(data_width)
    packed = Signal(range(per_beat))
    valid, byte, last = Signal(), Signal(8), Signal()
    beat_data = Signal(data_width)
    beat_keep = Signal(per_beat)
    beat_last, beat_valid = Signal(), Signal()
    m.d.comb += [sink.tdata.eq(beat_data), sink.tkeep.eq(beat_keep), sink.tlast.eq(beat_last),
                 sink.tvalid.eq(beat_valid)]
    can_move = ~beat_valid | sink.tready
    completes = (packed == per_beat - 1) | last
    ready = ~completes | can_move
    with m.If(beat_valid & sink.tready):
        m.d.sync += beat_valid.eq(0)
    with m.If(valid & ready):
        merged = packing | (byte << (packed * 8))
        with m.If(completes):
            m.d.sync += [beat_data.eq(merged), beat_keep.eq((Const(2, per_beat + 1) << packed) - 1),
                         beat_last.eq(last), beat_valid.eq(1), packing.eq(0), packed.eq(0)]
        with m.Else():
            m.d.sync += [packing.eq(merged), packed.eq(packed + 1)]
    return ByteSink(valid, byte, last, ready)
