"""A hardware sorter: ``std_msgs/msg/UInt32MultiArray`` in, the same numbers sorted out.

ReconROS's sorting node in hardware. The message arrives as its CDR body, byte by byte
(``_bytes``): the layout (its dimensions, labels included, and data offset) is walked and
skipped, the numbers are gathered into a block RAM, sorted there by a bottom-up merge sort
(two memories taking turns, one element a cycle, ``ceil(log2 n)`` passes), and sent back as
a message with an empty layout, as the software sorter publishes:
``UInt32MultiArray(data=sorted)``. ``capacity`` (an elaboration parameter) is the most
numbers a message may hold; a longer message is cut to its first ``capacity`` numbers, so
choose it from the node's largest input.
"""

from __future__ import annotations

from typing import Any

from amaranth import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..._errors import HardwareError
from ..streams._axi import axi_stream
from ..streams._bytes import bytes_in, bytes_out
from ..streams._ports import port_part

# the walk over UInt32MultiArray's CDR body, then the sort and the answer
(_DIMS, _LABEL_LEN, _LABEL, _PAD, _SIZE, _STRIDE, _OFFSET, _LENGTH, _DATA, _PAIR, _MERGE, _SEND,
 _SKIP) = range(13)
_HEADER = 12  # the answer's layout: no dimensions, data offset 0, then the length


class Sorter(wiring.Component):
    """Sorts the numbers of each ``UInt32MultiArray`` from ``source`` onto ``sink`` (see the module)."""

    def __init__(self, source: str, sink: str, data_width: int = 64, capacity: int = 2048) -> None:
        if capacity < 1:
            raise HardwareError(f"capacity must be at least 1 number, not {capacity!r}")
        self._source, self._sink = port_part(source), port_part(sink)
        self.data_width, self.capacity = data_width, capacity
        super().__init__({self._source: In(axi_stream(data_width)), self._sink: Out(axi_stream(data_width))})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        incoming = bytes_in(m, getattr(self, self._source), self.data_width)
        outgoing = bytes_out(m, getattr(self, self._sink), self.data_width)
        byte, take = incoming.byte, incoming.take
        index_bits = max(1, (self.capacity - 1).bit_length())

        memories = [Memory(shape=unsigned(32), depth=self.capacity, init=[]) for _ in range(2)]
        m.submodules.numbers_a, m.submodules.numbers_b = memories
        left = [memory.read_port(domain="comb") for memory in memories]
        right = [memory.read_port(domain="comb") for memory in memories]
        writes = [memory.write_port() for memory in memories]

        state = Signal(range(13))
        word = Signal(32)
        word_byte = Signal(2)
        new_word = Cat(word[8:], byte)
        word_done = word_byte == 3
        position = Signal(32)
        aligned_next = (position + 1)[:2] == 0
        remaining = Signal(32)  # bytes of a label; dimensions left in _SIZE/_STRIDE
        dimensions = Signal(32)
        count = Signal(32)  # numbers in the message
        kept = Signal(index_bits + 1)  # of them, what the memory holds
        gathered = Signal(index_bits + 1)
        width = Signal(index_bits + 2)  # of the runs merged in this pass
        low = Signal(index_bits + 2)
        i, j, k = Signal(index_bits + 2), Signal(index_bits + 2), Signal(index_bits + 2)
        source_memory = Signal()  # where this pass reads from (0: a, 1: b)
        sent = Signal(32)  # bytes of the answer

        middle = Mux(low + width < kept, low + width, kept)
        high = Mux(low + (width << 1) < kept, low + (width << 1), kept)
        read_left = Mux(source_memory, left[1].data, left[0].data)
        read_right = Mux(source_memory, right[1].data, right[0].data)
        sent_number = (sent - _HEADER)[2:]
        read_at = Mux(state == _SEND, sent_number, i)
        m.d.comb += [left[0].addr.eq(read_at), left[1].addr.eq(read_at), right[0].addr.eq(j), right[1].addr.eq(j)]

        def start_sort() -> list[object]:
            return [width.eq(1), low.eq(0), source_memory.eq(0), state.eq(_PAIR)]

        with m.Switch(state):
            with m.Case(_DIMS, _LABEL_LEN, _LABEL, _PAD, _SIZE, _STRIDE, _OFFSET, _LENGTH, _DATA, _SKIP):
                m.d.comb += take.eq(incoming.valid)
                with m.If(take):
                    m.d.sync += [position.eq(position + 1), word.eq(new_word), word_byte.eq(word_byte + 1)]
                    self._walk(m, state, new_word, word_done, aligned_next, remaining, dimensions, count, kept,
                               gathered, word_byte, writes[0], index_bits)
                    with m.If(incoming.last):
                        m.d.sync += [position.eq(0), word_byte.eq(0), *start_sort()]
            with m.Case(_PAIR):
                with m.If(width >= kept):
                    m.d.sync += [state.eq(_SEND), sent.eq(0), i.eq(0)]
                with m.Else():
                    m.d.sync += [i.eq(low), j.eq(middle), k.eq(low), state.eq(_MERGE)]
            with m.Case(_MERGE):
                from_left = (i < middle) & ((j >= high) | (read_left <= read_right))
                for which in (0, 1):
                    m.d.comb += [writes[which].addr.eq(k), writes[which].data.eq(Mux(from_left, read_left,
                                                                                      read_right)),
                                 writes[which].en.eq(source_memory != which)]
                m.d.sync += k.eq(k + 1)
                with m.If(from_left):
                    m.d.sync += i.eq(i + 1)
                with m.Else():
                    m.d.sync += j.eq(j + 1)
                with m.If(k + 1 >= high):
                    with m.If(high >= kept):  # the pass is done: the next reads what this one wrote
                        m.d.sync += [low.eq(0), width.eq(width << 1), source_memory.eq(~source_memory),
                                     state.eq(_PAIR)]
                    with m.Else():
                        m.d.sync += [low.eq(high), state.eq(_PAIR)]
            with m.Case(_SEND):
                total = _HEADER + (kept << 2)
                data_byte = sent - _HEADER
                number = Mux(source_memory, left[1].data, left[0].data)
                header = Cat(Const(0, 64), kept, Const(0, 32 - len(kept)))
                shown = Mux(sent < _HEADER, (header >> (sent[:4] << 3))[:8], (number >> (data_byte[:2] << 3))[:8])
                m.d.comb += [outgoing.valid.eq(1), outgoing.byte.eq(shown),
                             outgoing.last.eq(sent == total - 1)]
                with m.If(outgoing.ready):
                    m.d.sync += sent.eq(sent + 1)
                    with m.If(sent == total - 1):
                        m.d.sync += [state.eq(_DIMS), word_byte.eq(0), gathered.eq(0)]
        return m

    def _walk(self, m: Module, state: Signal, new_word: Any, word_done: Any, aligned_next: Any,
              remaining: Signal, dimensions: Signal, count: Signal, kept: Signal, gathered: Signal,
              word_byte: Signal, write: Any, index_bits: int) -> None:
        """One byte of the message's layout and numbers (its state's step)."""
        with m.Switch(state):
            with m.Case(_DIMS):
                with m.If(word_done):
                    m.d.sync += [dimensions.eq(new_word), state.eq(Mux(new_word == 0, _OFFSET, _LABEL_LEN))]
            with m.Case(_LABEL_LEN):
                with m.If(word_done):
                    m.d.sync += [remaining.eq(new_word), state.eq(Mux(new_word == 0, _SIZE, _LABEL))]
            with m.Case(_LABEL):
                m.d.sync += remaining.eq(remaining - 1)
                with m.If(remaining == 1):
                    m.d.sync += [state.eq(Mux(aligned_next, _SIZE, _PAD)), word_byte.eq(0)]
            with m.Case(_PAD):
                with m.If(aligned_next):
                    m.d.sync += [state.eq(_SIZE), word_byte.eq(0)]
            with m.Case(_SIZE):
                with m.If(word_done):
                    m.d.sync += state.eq(_STRIDE)
            with m.Case(_STRIDE):
                with m.If(word_done):
                    m.d.sync += [dimensions.eq(dimensions - 1), state.eq(Mux(dimensions == 1, _OFFSET, _LABEL_LEN))]
            with m.Case(_OFFSET):
                with m.If(word_done):
                    m.d.sync += state.eq(_LENGTH)
            with m.Case(_LENGTH):
                with m.If(word_done):
                    m.d.sync += [count.eq(new_word), gathered.eq(0), kept.eq(0), state.eq(Mux(new_word == 0, _SKIP,
                                                                                             _DATA))]
            with m.Case(_DATA):
                with m.If(word_done & (gathered < self.capacity)):
                    m.d.comb += [write.addr.eq(gathered[:index_bits]), write.data.eq(new_word), write.en.eq(1)]
                    m.d.sync += [gathered.eq(gathered + 1), kept.eq(gathered + 1)]
