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
    """Bytes packed into beats on ``sink`` (an ``Out(axi_stream)`` port, seen from inside).

    Two bytes wait in front of the packing, so ``ready`` is a register: neither the sink's TREADY nor
    the packing reaches the node's decisions in the cycle it changes (a byte-serial node's walk is
    long enough as it is)."""
    per_beat = data_width // 8
    valid, byte, last = Signal(), Signal(8), Signal()
    ready = Signal()
    waiting = [(Signal(name=f"waiting{i}"), Signal(8, name=f"waiting_byte{i}"), Signal(name=f"waiting_last{i}"))
               for i in range(2)]
    (first_full, first_byte, first_last), (second_full, second_byte, second_last) = waiting
    m.d.comb += ready.eq(~second_full)

    packing = Signal(data_width)
    packed = Signal(range(per_beat))
    beat_data = Signal(data_width)
    beat_keep = Signal(per_beat)
    beat_last, beat_valid = Signal(), Signal()
    m.d.comb += [sink.tdata.eq(beat_data), sink.tkeep.eq(beat_keep), sink.tlast.eq(beat_last),
                 sink.tvalid.eq(beat_valid)]
    can_move = ~beat_valid | sink.tready
    completes = (packed == per_beat - 1) | first_last
    packs = first_full & (~completes | can_move)
    with m.If(beat_valid & sink.tready):
        m.d.sync += beat_valid.eq(0)
    with m.If(packs):
        merged = packing | (first_byte << (packed * 8))
        with m.If(completes):
            m.d.sync += [beat_data.eq(merged), beat_keep.eq((Const(2, per_beat + 1) << packed) - 1),
                         beat_last.eq(first_last), beat_valid.eq(1), packing.eq(0), packed.eq(0)]
        with m.Else():
            m.d.sync += [packing.eq(merged), packed.eq(packed + 1)]

    pushes = valid & ready
    with m.If(packs):
        with m.If(second_full):
            m.d.sync += [first_byte.eq(second_byte), first_last.eq(second_last), second_full.eq(0)]
        with m.Elif(pushes):
            m.d.sync += [first_byte.eq(byte), first_last.eq(last)]
        with m.Else():
            m.d.sync += first_full.eq(0)
    with m.Elif(pushes):
        with m.If(first_full):
            m.d.sync += [second_full.eq(1), second_byte.eq(byte), second_last.eq(last)]
        with m.Else():
            m.d.sync += [first_full.eq(1), first_byte.eq(byte), first_last.eq(last)]
    return ByteSink(valid, byte, last, ready)
