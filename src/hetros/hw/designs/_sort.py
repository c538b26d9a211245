"""A hardware sorter: ``std_msgs/msg/UInt32MultiArray`` in, the same numbers sorted out.

ReconROS's sorting node in hardware. Every field of the message's CDR body is a uint32 at a
4-aligned offset (a dimension's label is skipped as the words it and its padding fill), so the
node walks the body a 32-bit word at a time. Why it looks as it does:

- **A whole beat a cycle in and out.** At a data width that is a power-of-two number of words (32,
  64, 128 … bits: ``lanes`` words a beat) the numbers are written a beat a cycle into ``lanes``
  banks of block RAM, number ``n`` in bank ``n % lanes``: the numbers of one beat land in distinct
  banks whatever word of the beat they start at, so no realignment register is needed; the answer
  leaves a beat a cycle the same way. Other widths gather each word a byte a cycle.
- **Block RAM, synchronous reads.** The sort is bottom-up merge (two memories taking turns,
  ``ceil(log2 n)`` passes, one number a cycle). Each run being merged is read through a three-entry
  prefetch buffer, so the comparison starts from registers and no block RAM output feeds an
  address in the same cycle; writes are registered. ``capacity`` (an elaboration parameter) is the
  most numbers a message may hold; the gateway refuses a longer one (``check_message``), naming
  the capacity to set.
- **Registered ready.** The answer leaves through a skid buffer, so a downstream TREADY reaches no
  register of the sorter, and the input comes through a register slice, so its TREADY is a register.
"""

from __future__ import annotations

from typing import Any

from amaranth import Array, Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..._errors import HardwareError
from ..streams._axi import SkidInput, axi_stream, register_slice, skid_buffer
from ..streams._bytes import bytes_in, bytes_out
from ..streams._ports import port_part

# the walk over UInt32MultiArray's CDR body a word at a time, then the sort and the answer
(_DIMS, _LABEL_LEN, _LABEL, _SIZE, _STRIDE, _OFFSET, _LENGTH, _DATA, _SKIP, _ENDED, _PASS, _MERGE,
 _SEND) = range(13)
_HEADER_WORDS = 3  # the answer's layout: no dimensions, data offset 0, then the length
_READ_LATENCY = 2  # a block RAM read, then its register (ECP5: the block's own output register)
_PREFETCH = _READ_LATENCY + 2  # numbers a run's buffer holds: enough for one a cycle


class Sorter(wiring.Component):
    """Sorts the numbers of each ``UInt32MultiArray`` from ``source`` onto ``sink`` (see the module)."""

    def __init__(self, source: str, sink: str, data_width: int = 64, capacity: int = 2048) -> None:
        if capacity < 1:
            raise HardwareError(f"capacity must be at least 1 number, not {capacity!r}")
        self._source, self._sink = port_part(source), port_part(sink)
        self.data_width, self.capacity = data_width, capacity
        words = data_width // 32
        self.full_width = data_width % 32 == 0 and not words & (words - 1)
        self.lanes = words if self.full_width else 1
        super().__init__({self._source: In(axi_stream(data_width)), self._sink: Out(axi_stream(data_width))})

    def check_message(self, topic: str, message: Any) -> None:
        """A message longer than the block RAM would be cut short in hardware: refused before it goes in."""
        count = len(message.data)
        if count > self.capacity:
            raise HardwareError(f"an array of {count} numbers is longer than the sorter's block RAM ({self.capacity} "
                                f"numbers, its capacity parameter): set capacity to at least {count}, or send "
                                "shorter arrays")

    def elaborate(self, platform: object) -> Module:
        m = Module()
        lanes = self.lanes
        shift = lanes.bit_length() - 1
        depth = -(-self.capacity // lanes)
        count_bits = (4 * self.capacity + lanes).bit_length() + 1  # a run's next segment may start past the end
        group, have, at, group_last, consume = self._words_in(m)
        push = self._words_out(m)

        # two memories taking turns, each ``lanes`` banks; a bank's two read ports feed the two runs
        banks = [[Memory(shape=unsigned(32), depth=depth, init=[]) for _ in range(lanes)] for _ in range(2)]
        for which, memory_banks in enumerate(banks):
            for bank, memory in enumerate(memory_banks):
                m.submodules[f"numbers{which}_{bank}"] = memory
        left = [[memory.read_port(domain="sync") for memory in memory_banks] for memory_banks in banks]
        right = [[memory.read_port(domain="sync") for memory in memory_banks] for memory_banks in banks]
        writes = [[memory.write_port() for memory in memory_banks] for memory_banks in banks]
        write_en = [[Signal(name=f"write_en{w}_{b}") for b in range(lanes)] for w in range(2)]
        write_addr = [[Signal(range(depth), name=f"write_addr{w}_{b}") for b in range(lanes)] for w in range(2)]
        write_data = [[Signal(32, name=f"write_data{w}_{b}") for b in range(lanes)] for w in range(2)]
        for which in range(2):
            for bank in range(lanes):
                port = writes[which][bank]
                m.d.comb += [port.en.eq(write_en[which][bank]), port.addr.eq(write_addr[which][bank]),
                             port.data.eq(write_data[which][bank])]
                m.d.sync += write_en[which][bank].eq(0)

        state = Signal(range(13))
        dimensions = Signal(32)
        remaining = Signal(32)  # words of a label
        to_take = Signal(32)  # numbers of the message not yet taken
        gathered = Signal(count_bits)  # numbers written (at most capacity)
        plenty_to_take, plenty_of_space = Signal(), Signal()  # more than a beat's numbers, this cycle
        m.d.sync += [plenty_to_take.eq(to_take > 2 * lanes), plenty_of_space.eq(gathered + 2 * lanes < self.capacity)]
        kept = Signal(count_bits)
        width = Signal(count_bits + 1)  # of the runs merged in this pass
        source_memory = Signal()  # where this pass reads from; the other is written

        # --- the walk: one word of the layout a cycle, then the numbers a beat at a time ----------------
        available = Signal(range(lanes + 1))
        word = Signal(32)
        m.d.comb += [available.eq(have - at), word.eq(Array(group)[at])]
        walking = (state <= _SKIP)
        ends_group = Signal()
        m.d.comb += ends_group.eq((available != 0) & (at + consume == have))
        with m.If(walking & (available != 0)):
            with m.Switch(state):
                with m.Case(_DATA):
                    # a beat's numbers are checked against small values only: ``plenty`` says (from last
                    # cycle's counts, which move by at most a beat) that more than a beat of numbers is to
                    # come and more than a beat fits; otherwise the counts are small, and their low bits are
                    # them, so no 32-bit comparison decides a write
                    small = (2 * lanes).bit_length() + 1
                    last_few = to_take[:small]
                    space = Signal(small)
                    taken, written = Signal(range(lanes + 1)), Signal(range(lanes + 1))
                    m.d.comb += [space.eq(Const(self.capacity % (1 << small), small) - gathered[:small]),
                                 taken.eq(Mux(plenty_to_take | (available <= last_few), available, last_few)),
                                 written.eq(Mux(plenty_of_space | (taken <= space), taken, space)),
                                 consume.eq(taken)]
                    m.d.sync += [to_take.eq(to_take - taken), gathered.eq(gathered + written)]
                    with m.If(~plenty_to_take & (last_few <= available)):
                        m.d.sync += state.eq(_SKIP)
                    offset = gathered[:shift] if shift else Const(0, 1)
                    for bank in range(lanes):
                        step = Signal(range(lanes), name=f"step{bank}")  # this bank's number is the step-th taken
                        m.d.comb += step.eq((bank - offset)[:shift] if shift else 0)
                        with m.If(step < written):
                            m.d.sync += [write_en[0][bank].eq(1), write_addr[0][bank].eq((gathered + step) >> shift),
                                         write_data[0][bank].eq(Array(group)[(at + step)[:max(1, shift + 1)]])]
                with m.Case(_SKIP):
                    m.d.comb += consume.eq(available)
                with m.Default():
                    m.d.comb += consume.eq(1)
                    self._walk(m, state, word, dimensions, remaining)
                    with m.If(state == _LENGTH):
                        m.d.sync += [to_take.eq(word), gathered.eq(0), plenty_to_take.eq(word > 2 * lanes),
                                     plenty_of_space.eq(self.capacity > 2 * lanes)]
            with m.If(group_last & ends_group):
                m.d.sync += state.eq(_ENDED)

        # --- the sort: every pass one stream of pairs, a number a cycle -------------------------------------
        runs = [_Run(m, "left", count_bits, lanes), _Run(m, "right", count_bits, lanes)]
        for run, ports in zip(runs, (left, right), strict=True):
            run.connect(m, ports, source_memory, shift)
        left_run, right_run = runs
        from_left = ~left_run.done & (right_run.done | (left_run.head <= right_run.head))
        moves = (left_run.done | left_run.ready) & (right_run.done | right_run.ready) & ~(left_run.done
                                                                                        & right_run.done)
        k = Signal(count_bits)  # the number being written
        # the next pair's bounds (its first number, its right run's first, its end), stepped by 2 * width as
        # each pair ends, and its takes from each run a register behind them (a pair that is not a pass's
        # last lasts two cycles or more): each a comparison of two registers, no adder before it
        next_bounds = [Signal(count_bits, name=f"next_{n}") for n in ("base", "middle", "end")]
        next_base, next_middle, next_end = next_bounds
        next_left, next_right = Signal(count_bits), Signal(count_bits)
        m.d.sync += [next_left.eq(Mux(next_middle <= kept, width, kept - next_base)),
                     next_right.eq(Mux(next_end <= kept, width, Mux(next_middle < kept, kept - next_middle, 0)))]
        answer_beats = Signal(count_bits)
        answer = _Answer(lanes, count_bits)
        with m.Switch(state):
            with m.Case(_ENDED):  # the last registered write lands this cycle
                m.d.sync += [kept.eq(gathered), width.eq(1),
                             source_memory.eq(0), state.eq(_PASS)]
            with m.Case(_PASS):
                with m.If(width >= kept):
                    m.d.sync += [state.eq(_SEND), answer_beats.eq((kept + _HEADER_WORDS + lanes - 1) >> shift)]
                    answer.start(m)
                with m.Else():
                    m.d.sync += [k.eq(0), state.eq(_MERGE), next_base.eq(width << 1),
                                 next_middle.eq((width << 1) + width), next_end.eq(width << 2)]
                    left_run.start(m, False, width, kept)
                    right_run.start(m, True, width, kept)
            with m.Case(_MERGE):
                left_run.step(m, moves & from_left, width, kept)
                right_run.step(m, moves & ~from_left, width, kept)
                with m.If(moves):
                    value = Mux(from_left, left_run.head, right_run.head)
                    for which in range(2):
                        with m.If(source_memory != which):
                            for bank in range(lanes):
                                with m.If((k[:shift] == bank) if shift else 1):
                                    m.d.sync += [write_en[which][bank].eq(1), write_addr[which][bank].eq(k >> shift),
                                                 write_data[which][bank].eq(value)]
                    m.d.sync += k.eq(k + 1)
                    pair_ends = Mux(from_left, (left_run.take == 1) & right_run.done,
                                    (right_run.take == 1) & left_run.done)
                    with m.If(k + 1 == kept):  # the pass is done: the next reads what this one wrote
                        m.d.sync += [width.eq(width << 1), source_memory.eq(~source_memory), state.eq(_PASS)]
                    with m.Elif(pair_ends):
                        m.d.sync += [*(bound.eq(bound + (width << 1)) for bound in next_bounds),
                                     left_run.take.eq(next_left), right_run.take.eq(next_right)]
            with m.Case(_SEND):
                answer.send(m, push, left, source_memory, kept, answer_beats, state, gathered)
        return m

    def _walk(self, m: Module, state: Signal, word: Signal, dimensions: Signal, remaining: Signal) -> None:
        """One word of the message's layout (its state's step)."""
        with m.Switch(state):
            with m.Case(_DIMS):
                m.d.sync += [dimensions.eq(word), state.eq(Mux(word == 0, _OFFSET, _LABEL_LEN))]
            with m.Case(_LABEL_LEN):  # the label's bytes (its NUL included) and padding, in words
                m.d.sync += [remaining.eq((word + 3) >> 2), state.eq(Mux(word == 0, _SIZE, _LABEL))]
            with m.Case(_LABEL):
                m.d.sync += remaining.eq(remaining - 1)
                with m.If(remaining == 1):
                    m.d.sync += state.eq(_SIZE)
            with m.Case(_SIZE):
                m.d.sync += state.eq(_STRIDE)
            with m.Case(_STRIDE):
                m.d.sync += [dimensions.eq(dimensions - 1), state.eq(Mux(dimensions == 1, _OFFSET, _LABEL_LEN))]
            with m.Case(_OFFSET):
                m.d.sync += state.eq(_LENGTH)
            with m.Case(_LENGTH):
                m.d.sync += state.eq(Mux(word == 0, _SKIP, _DATA))

    def _words_in(self, m: Module) -> tuple[list[Signal], Signal, Signal, Signal, Signal]:
        """The input as a held group of words (a beat of them at full width, else one gathered from bytes):
        the walk takes ``consume`` words a cycle from word ``at``; the next group loads as the last goes."""
        lanes = self.lanes
        source = register_slice(m, getattr(self, self._source), self.data_width)
        group = [Signal(32, name=f"word{i}") for i in range(lanes)]
        have, at = Signal(range(lanes + 1)), Signal(range(lanes + 1))
        group_last = Signal()
        consume = Signal(range(lanes + 1))
        empties = (have == 0) | (at + consume == have)
        with m.If(consume != 0):
            m.d.sync += at.eq(at + consume)
            with m.If(at + consume == have):
                m.d.sync += [have.eq(0), at.eq(0)]
        if self.full_width:
            m.d.comb += source.tready.eq(empties)
            with m.If(source.tvalid & empties):
                m.d.sync += [*(group[i].eq(source.tdata.word_select(i, 32)) for i in range(lanes)),
                             have.eq(sum(source.tkeep[4 * i] for i in range(lanes))), at.eq(0),
                             group_last.eq(source.tlast)]
            return group, have, at, group_last, consume
        incoming = bytes_in(m, source, self.data_width)
        partial = Signal(24)
        partial_bytes = Signal(range(4))
        completes = (partial_bytes == 3) | incoming.last
        m.d.comb += incoming.take.eq(incoming.valid & (~completes | empties))
        with m.If(incoming.take):
            with m.If(completes):
                whole = Cat(partial, Const(0, 8)) | (incoming.byte << (partial_bytes * 8))
                m.d.sync += [group[0].eq(whole), have.eq(1), at.eq(0), group_last.eq(incoming.last),
                             partial.eq(0), partial_bytes.eq(0)]
            with m.Else():
                m.d.sync += [partial.eq(partial | (incoming.byte << (partial_bytes * 8))),
                             partial_bytes.eq(partial_bytes + 1)]
        return group, have, at, group_last, consume

    def _words_out(self, m: Module) -> SkidInput:
        """Where the answer's beats of words go: the skid buffer at full width, else a word register the
        bytes leave from (``room`` is a register either way)."""
        sink = getattr(self, self._sink)
        if self.full_width:
            return skid_buffer(m, sink, self.data_width)
        given = SkidInput(Signal(name="push"), Signal(32, name="push_data"), Signal(4, name="push_keep"),
                          Signal(name="push_last"), Signal(name="room"))
        outgoing = bytes_out(m, sink, self.data_width)
        serial, serial_last = Signal(32), Signal()
        serial_bytes = Signal(range(5))
        m.d.comb += [given.room.eq(serial_bytes == 0), outgoing.valid.eq(serial_bytes != 0),
                     outgoing.byte.eq(serial[:8]), outgoing.last.eq(serial_last & (serial_bytes == 1))]
        with m.If(given.push):
            m.d.sync += [serial.eq(given.data), serial_last.eq(given.last),
                         serial_bytes.eq(Mux(given.keep[3], 4, Mux(given.keep[2], 3, Mux(given.keep[1], 2, 1))))]
        with m.Elif(outgoing.valid & outgoing.ready):
            m.d.sync += [serial.eq(serial >> 8), serial_bytes.eq(serial_bytes - 1)]
        return given


class _Answer:
    """The answer, a beat a cycle: the header's three words, then the numbers from the banks.

    Beat ``t`` holds words ``t * lanes …`` of the answer; word ``p`` past the header is number
    ``p - 3``, so bank ``b`` of beat ``t`` is read at a fixed offset from ``t`` and lands at a fixed
    word of the beat: the rotation is wiring. Three stages, the read ports, their registers and the
    beat, move together while the skid buffer has room (a register): no block RAM output and no
    TREADY decides anything in the cycle it arrives."""

    def __init__(self, lanes: int, count_bits: int) -> None:
        self.lanes = lanes
        self.next_beat, self.read_beat = Signal(count_bits, name="next_beat"), Signal(count_bits, name="read_beat")
        self.read, self.held_valid, self.staged = Signal(name="read_valid"), Signal(name="held_valid"), Signal(
            name="staged_valid")

    def start(self, m: Module) -> None:
        m.d.sync += [self.next_beat.eq(0), self.read.eq(0), self.held_valid.eq(0), self.staged.eq(0)]

    def send(self, m: Module, push: SkidInput, ports: list[list[Any]], source_memory: Signal, kept: Signal,
             answer_beats: Signal, state: Signal, gathered: Signal) -> None:
        """A cycle of the answer (while the sorter is in ``_SEND``)."""
        lanes = self.lanes
        next_beat, read_beat, read, staged = self.next_beat, self.read_beat, self.read, self.staged
        staged_data = Signal(len(push.data))
        staged_last = Signal()
        staged_keep = Signal(len(push.keep))
        advance = ~staged | push.room
        issue = advance & (next_beat < answer_beats)
        for which in range(2):
            for bank, port in enumerate(ports[which]):
                offset = ((bank + _HEADER_WORDS) % lanes - _HEADER_WORDS) // lanes
                m.d.comb += [port.addr.eq(next_beat + offset), port.en.eq(issue & (source_memory == which))]
        # the read ports' registers (the second stage), moving with the rest
        held = [[Signal(32, name=f"answer_held{which}_{bank}") for bank in range(lanes)] for which in range(2)]
        held_valid, held_beat = self.held_valid, Signal.like(read_beat)
        words = []
        for position in range(lanes):
            place = held_beat * lanes + position
            number = Array(Array(banks) for banks in held)[source_memory][(position - _HEADER_WORDS) % lanes]
            words.append(Mux(place < _HEADER_WORDS, Mux(place == _HEADER_WORDS - 1, kept, 0), number))
        words_left = kept + _HEADER_WORDS - held_beat * lanes
        last = words_left <= lanes
        keep_words = Mux(last, words_left, lanes)
        with m.If(advance):
            m.d.sync += [staged.eq(held_valid), staged_data.eq(Cat(*words)), staged_last.eq(last),
                         staged_keep.eq(Cat(*(Const(0b1111, 4) if i == 0 else Mux(keep_words > i, 0b1111, 0)
                                              for i in range(lanes)))),
                         held_valid.eq(read), held_beat.eq(read_beat),
                         *(held[which][bank].eq(port.data) for which in range(2)
                           for bank, port in enumerate(ports[which])),
                         read.eq(issue), read_beat.eq(next_beat)]
            with m.If(issue):
                m.d.sync += next_beat.eq(next_beat + 1)
        pushes = staged & push.room
        m.d.comb += [push.push.eq(pushes), push.data.eq(staged_data), push.last.eq(staged_last),
                     push.keep.eq(staged_keep)]
        with m.If(pushes & staged_last):
            m.d.sync += [state.eq(_DIMS), gathered.eq(0)]


class _Run:
    """One of the two runs of every pair in a merge pass: numbers ``[start, start + width)`` of every
    ``2 * width``, from ``offset`` on (0 for the left runs, ``width`` for the right), fetched ahead into a
    buffer of ``_PREFETCH`` (``head``, a register, and a ring behind it). The fetch runs on into the next pair's run
    while this pair is merged: a pass is one stream, with no gap between pairs."""

    def __init__(self, m: Module, name: str, count_bits: int, lanes: int) -> None:
        self.fetch = Signal(count_bits, name=f"{name}_fetch")  # the next number to read
        self.next_start = Signal(count_bits, name=f"{name}_next_start")  # the next segment's bounds
        self.next_stop = Signal(count_bits, name=f"{name}_next_stop")  # (before clipping at the end)
        self.segment_end = Signal(count_bits, name=f"{name}_segment_end")
        self.take = Signal(count_bits, name=f"{name}_take")  # numbers of this pair not yet taken from it
        self.buffered = Signal(range(_PREFETCH + 1), name=f"{name}_buffered")  # head and ring
        self.flight = [Signal(name=f"{name}_flight{i}") for i in range(_READ_LATENCY)]  # reads 1, 2 cycles old
        self.banks = [Signal(range(lanes), name=f"{name}_bank{i}") for i in range(_READ_LATENCY)]  # of each read
        self.bank = self.banks[-1]
        self.arrived = Signal(32, name=f"{name}_arrived")  # the read two cycles old, from its bank's register
        # the head, a register of its own, and a ring behind it that every arrival enters (so the ring's
        # writes do not wait for the comparison): a take reloads the head and moves ``first`` on, some forty
        # flip-flops a run where a shifting buffer had a hundred and thirty
        self.head = Signal(32, name=f"{name}_head")
        self.head_valid = Signal(name=f"{name}_head_valid")
        self.ring = [Signal(32, name=f"{name}_ring{i}") for i in range(_PREFETCH - 1)]
        self.first = Signal(range(_PREFETCH - 1), name=f"{name}_first")
        self.free = Signal(range(_PREFETCH - 1), name=f"{name}_free")
        self.in_ring = Signal(range(_PREFETCH), name=f"{name}_in_ring")
        self.done = Signal(name=f"{name}_done")
        self.ready = Signal(name=f"{name}_ready")
        self.issue = Signal(name=f"{name}_issue")
        m.d.comb += [self.done.eq(self.take == 0), self.ready.eq(self.head_valid),
                     self.buffered.eq(self.head_valid + self.in_ring)]

    def connect(self, m: Module, ports: list[list[Any]], source_memory: Signal, shift: int) -> None:
        """Drive both memories' read ports of this run (while merging) and register what arrives."""
        data = Array(Array(_registered(m, port.data) for port in memory_ports) for memory_ports in ports)
        m.d.comb += self.arrived.eq(data[source_memory][self.bank])
        for memory_ports in ports:
            for port in memory_ports:
                m.d.comb += port.addr.eq(self.fetch >> shift)
        self._ports, self._shift = ports, shift

    def start(self, m: Module, right: bool, width: Signal, kept: Signal) -> None:
        """A pass begins: this run's first segment (``[0, width)``, or ``[width, 2 * width)`` for the
        ``right`` runs) and the first pair's takes, each a comparison and a choice."""
        twice = width << 1
        if right:
            end, take = Mux(twice < kept, twice, kept), Mux(twice < kept, width, Mux(width < kept, kept - width, 0))
            bounds = [self.fetch.eq(width), self.next_start.eq(twice + width), self.next_stop.eq(width << 2)]
        else:
            end = take = Mux(width < kept, width, kept)
            bounds = [self.fetch.eq(0), self.next_start.eq(twice), self.next_stop.eq(twice + width)]
        m.d.sync += [*bounds, self.segment_end.eq(end), self.take.eq(take), self.head_valid.eq(0),
                     self.in_ring.eq(0), self.first.eq(0), self.free.eq(0), *(flight.eq(0) for flight in self.flight)]

    def step(self, m: Module, takes: Any, width: Signal, kept: Signal) -> None:
        """A merge cycle: read ahead while the buffer (and what is in flight) has room; take the head when
        ``takes``; the number read two cycles ago joins the buffer behind what stays."""
        in_flight = sum(self.flight)
        m.d.comb += self.issue.eq((self.fetch < self.segment_end) & (self.buffered + in_flight < _PREFETCH))
        for memory_ports in self._ports:
            for port in memory_ports:
                m.d.comb += port.en.eq(self.issue)
        m.d.sync += [self.flight[0].eq(self.issue), self.flight[1].eq(self.flight[0]),
                     self.banks[0].eq(self.fetch[:self._shift] if self._shift else 0), self.banks[1].eq(self.banks[0])]
        with m.If(self.issue):
            with m.If(self.fetch + 1 == self.segment_end):
                m.d.sync += [self.fetch.eq(self.next_start), self.next_start.eq(self.next_start + (width << 1)),
                             self.next_stop.eq(self.next_stop + (width << 1)),
                             self.segment_end.eq(Mux(self.next_stop < kept, self.next_stop, kept))]
            with m.Else():
                m.d.sync += self.fetch.eq(self.fetch + 1)
        landing = self.flight[-1]
        last = _PREFETCH - 2
        with m.If(landing):
            m.d.sync += [Array(self.ring)[self.free].eq(self.arrived),
                         self.free.eq(Mux(self.free == last, 0, self.free + 1))]
        refill = takes | ~self.head_valid  # the head is taken or empty: the ring's first (or what lands) moves up
        moves_up = refill & ((self.in_ring != 0) | landing)
        with m.If(refill):
            m.d.sync += [self.head.eq(Mux(self.in_ring != 0, Array(self.ring)[self.first], self.arrived)),
                         self.head_valid.eq(moves_up)]
        with m.If(moves_up):
            m.d.sync += self.first.eq(Mux(self.first == last, 0, self.first + 1))
        m.d.sync += self.in_ring.eq(self.in_ring + landing - moves_up)
        with m.If(takes):
            m.d.sync += self.take.eq(self.take - 1)


def _registered(m: Module, value: Any) -> Signal:
    """``value`` a cycle later: after a block RAM read port, the register its output drives alone (Yosys can
    take it into the block RAM), so the multiplexers behind it start from a flip-flop."""
    register = Signal.like(value)
    m.d.sync += register.eq(value)
    return register

