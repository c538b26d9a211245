"""The full-width datapath of the 3x3 image filters: a whole beat of pixel bytes a clock cycle.

``_image`` gives each filter its kernel; this module moves the message. Why it looks as it does:

- **Beats stay beats.** A line is a whole number of beats (the node refuses other images in
  software), so the rows above and below a byte are the same lane ``step / lanes`` beats back and
  forth, whatever the byte offset at which the pixels start: the line buffers are two rings of
  beats, and no byte of the message is shifted to another lane on its way through. Bytes before the
  pixels in the first pixel beat leave as they came.
- **The header is walked a 4-byte word a cycle.** Every field after ``frame_id`` that the walk needs
  is a uint32 at a 4-aligned offset of the CDR body, and the strings are skipped a word at a time,
  so a beat of header takes ``lanes / 4`` cycles: some 15 cycles a message, against one cycle per
  beat of pixels.
- **No stall inside, registered ready at both ends.** The pipeline's registers move every cycle
  (no enable fans out to thousands of them): a beat is let in only while the output FIFO has room
  for it and every beat already on its way (credits counted from the step that makes a beat to
  the FIFO giving it away), so a downstream node's TREADY reaches only the FIFO; the input is two
  beats that the stream writes in turn, so this node's TREADY is a register and none of its
  decisions reaches the enable of a data register (chains meet their clock one node at a time).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol, TypeVar

from amaranth import Cat, Const, Module, Mux, Signal, signed, unsigned
from amaranth.hdl import Value
from amaranth.lib import fifo
from amaranth.lib.memory import Memory

from ..._errors import HardwareError

_Made = TypeVar("_Made")

_FIFO_SLICE = 64  # bits of the output FIFO's entry that share a pair of pointers
_STEP_SLICE = 64  # bits of the window's registers that load on one copy of the step
_BLOCK_RAM_RINGS = 256  # stream width from which the line-buffer rings are block RAM

# steps between a beat coming in and the window whose bottom row it completes going out
_LAG = 3
# the header walk, a 4-byte word at a time
_STAMP, _STAMP_NS, _FRAME_LEN, _FRAME, _HEIGHT, _WIDTH, _ENC_LEN, _ENC, _STEP, _DATA_LEN, _DATA = range(11)


class Pipe:
    """The pipeline's registers: :meth:`reg` is a value one stage later. They move every cycle (the
    datapath takes a beat in only when there is room for it at the end), so ``advance`` is always high;
    a kernel that drives a block RAM's read enable from it stays right if that changes."""

    def __init__(self, m: Module) -> None:
        self.m, self.advance = m, Const(1, 1)
        self._count = 0
        self._shared: dict[tuple[object, ...], Any] = {}

    def shared(self, what: str, values: Sequence[Value], make: Callable[[], _Made]) -> _Made:
        """``make()`` once for ``what`` on the same bytes of the same beat: a lane's window shares its
        columns with the lanes a pixel to each side, and so does the work done on a column alone."""
        key = (what, *((id(getattr(v, "value", v)), getattr(v, "start", 0), getattr(v, "stop", 0)) for v in values))
        if key not in self._shared:
            self._shared[key] = make()
        made: _Made = self._shared[key]
        return made

    def reg(self, value: Value, name: str = "stage") -> Signal:
        self._count += 1
        held = Signal(value.shape(), name=f"{name}_{self._count}")
        self.m.d.sync += held.eq(value)
        return held

    def delay(self, value: Value, stages: int, name: str = "delayed") -> Value:
        for _ in range(stages):
            value = self.reg(value, name)
        return value


class LaneFilter(Protocol):
    """What a filter gives this datapath: its window kernel and its per-frame hooks, lane by lane."""

    channels: int
    width: int
    kernel_stages: int
    post_stages: int

    def lane_kernel(self, pipe: Pipe, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value: ...

    def post_lanes(self, m: Module, pipe: Pipe, values: list[Value]) -> list[Value]: ...

    def observe_lanes(self, m: Module, values: list[Value], pixels: list[Value], taken: list[Value],
                      count: Value) -> None: ...

    def between_frames_lanes(self, m: Module, ended: Value) -> Value: ...


def elaborate_lanes(node: LaneFilter, m: Module, source: Any, sink: Any, data_width: int) -> None:
    """Build the full-width filter of ``node`` between ``source`` and ``sink`` in ``m``."""
    lanes = data_width // 8
    words = lanes // 4
    channels = node.channels
    depth = max(1, -(-node.width * channels // lanes))

    # the step through the pixels loads the window's registers, a slice of the beat at a time, each slice on
    # a copy of the step of its own (a copy of each register it is decided from, kept apart by its own
    # feedback, which synthesis cannot prove the same): one step to every window register (thirteen beats)
    # was one net of over 6,600 clock enables at 512 bits. Copy 0 is the control's alone (counters,
    # the walk's state), so that its few registers sit together: on a copy that also loaded a slice, the
    # control was spread over the device (16.2 ns, 13.6 of them routing, on the 512-bit blur); copy 1 moves
    # the line-buffer rings, whose block RAMs stand in columns across the device (on the control's copy,
    # they pulled it apart again: 11.8 of 13.2 ns routing). Slice k loads on copy k + 2.
    slices = max(1, data_width // _STEP_SLICE)
    slice_bits = data_width // slices
    copies = slices + 2
    # the held input beat (``hold``): the header walk reads it a word at a time; the pixels step through it
    hold, hold_keep, hold_last, held_copies, release = _input_pair(m, source, data_width, slices, copies)

    # output: a FIFO deep enough for every beat the pipeline may hold; a beat is counted (``outstanding``)
    # from the step that makes it until the FIFO gives it away, and a step is taken only while one more
    # fits, so the pipeline never stalls: its registers have no enable, and no stall signal fans out to
    # thousands of them (the lane-following target's critical path was that net)
    # The FIFO is a FIFO per 64 bits of the entry, in step, each with pointers of its own: one FIFO's read
    # pointer would drive every distributed-RAM cell of a wide beat (145 at 512 bits), a net too long
    # for the clock.
    out_depth = node.kernel_stages + node.post_stages + 5
    entry_bits = data_width + lanes + 1  # the beat, its keep and its last
    out_fifos = []
    for index, start in enumerate(range(0, entry_bits, _FIFO_SLICE)):
        width = min(_FIFO_SLICE, entry_bits - start)
        m.submodules[f"out_fifo{index}"] = part = fifo.SyncFIFOBuffered(width=width, depth=out_depth)
        m.d.comb += part.r_en.eq(sink.tready)
        out_fifos.append(part)
    out_ready = out_fifos[0].r_rdy  # every slice holds the same number of entries
    m.d.comb += [sink.tvalid.eq(out_ready),
                 Cat(sink.tdata, sink.tkeep, sink.tlast).eq(Cat(*(part.r_data for part in out_fifos)))]
    # Whether one more beat fits (``room``) is a register, decided from registers alone: the count takes
    # a step's reservation a cycle late (``reserved_late``) and the room keeps a place for it. Decided
    # from the step itself, it closed a loop through the control (room, step, reservation, count, room)
    # that was the 512-bit blur's critical path.
    reserved, reserved_late = Signal(), Signal()
    m.d.sync += reserved_late.eq(reserved)
    rooms = []
    for copy in range(copies):
        outstanding = Signal(range(out_depth + 2), name=f"outstanding{copy}")
        following = Signal(range(out_depth + 2), name=f"following{copy}")
        rooms.append(Signal(init=1, name=f"room{copy}"))
        m.d.comb += following.eq(outstanding + reserved_late - (out_ready & sink.tready))
        m.d.sync += [outstanding.eq(following), rooms[-1].eq(following + 2 <= out_depth)]

    # --- the header walk ---------------------------------------------------------------------------------
    bits = (node.width * channels + 2 * lanes).bit_length() + 1  # a line's bytes and then some
    until_window = Signal(bits)  # steps of this message before the first that fills a window
    window_due = Signal(init=1)  # until_window == 0, as a register (the first window's step loads hundreds)
    state = Signal(range(11))
    # state is _DATA, as a register a copy: a copy's pick and step are decided from registers of its own,
    # which sit by the slice they load (one register of the control's to every copy's step, then the step
    # to the slice, were two nets across the device in series: the 512-bit compensation's critical path)
    pixel_copies = [Signal(name=f"in_pixels{copy}") for copy in range(copies)]
    at_data_len = Signal()  # state is _DATA_LEN, as one register (the beat's end is decided from it)
    unit = Signal(range(max(2, words)))
    remaining = Signal(32)
    step, data_len = Signal(32), Signal(32)
    start = Signal(range(lanes))  # the byte of the first pixel beat at which the pixels begin
    # a word is read in two cycles: picked out of the beat and held, then walked (the walk's decisions then
    # start from registers, which keeps this small state machine off the design's critical path)
    word, word_zero, phase = Signal(32), Signal(), Signal()
    busy = Signal()  # the node works between two frames (its between_frames_lanes), so the next one waits
    header_ended = Signal()  # the last message ended in its header: the walk starts over
    # a beat's first word is picked from the held beat, and the words after it move on in ``ahead``, one further
    # at each pick: a multiplexer of the beat's words indexed by ``unit`` was the 512-bit compensation's critical
    # path once the design routed (ten logic levels from ``unit`` to ``word_zero``). ``ahead`` moves a slice at
    # a time, each on copies of its own of the pick and of whether the beat's first word is next (a pick and a
    # select of all 480 bits were the 512-bit blur's critical path, 11.1 ns of routing); a copy is decided from
    # the copies of the held beat's count or of the room, which keeps synthesis from merging it with the others
    picks = [Signal(name=f"picking{copy}") for copy in range(copies)]
    m.d.comb += [pick.eq(held & ~copy_pixels & ~busy & ~phase & ~header_ended)
                 for pick, held, copy_pixels in zip(picks, held_copies, pixel_copies, strict=True)]
    picking = picks[0]
    firsts = [Signal(init=1, name=f"first_unit{copy}") for copy in range(copies)]  # unit is 0, as registers
    ahead = Signal(max(1, data_width - 32))  # the held beat's words after the one last picked, the next lowest
    with m.If(picking):
        picked = hold[:32] if words == 1 else Mux(firsts[0], hold[:32], ahead[:32])
        m.d.sync += [word.eq(picked), word_zero.eq(picked == 0), phase.eq(1)]
    for index in range(slices if words > 1 else 0):
        bits_of = slice(index * slice_bits, min((index + 1) * slice_bits, len(ahead)))
        if bits_of.start < bits_of.stop:
            with m.If(picks[index + 2]):
                m.d.sync += ahead[bits_of].eq(Mux(firsts[index + 2], hold[32:], ahead[32:])[bits_of])
    last_unit = Signal(init=words == 1)  # unit is the beat's last word, as a register
    pixels_here = at_data_len & ~last_unit & ~word_zero  # the pixels begin inside this beat
    beat_read = last_unit | pixels_here
    header_leaves = Signal()
    walks = [Signal(name=f"walking{copy}") for copy in range(copies)]
    m.d.comb += [walk.eq(phase & (~beat_read | pixels_here | copy_room)) for walk, copy_room in zip(walks, rooms,
                                                                                                     strict=True)]
    walking = walks[0]
    m.d.comb += header_leaves.eq(walking & beat_read & ~pixels_here)
    for walk, first in zip(walks, firsts, strict=True):
        with m.If(walk):
            m.d.sync += first.eq(beat_read)
    with m.If(walking):
        m.d.sync += phase.eq(0)
    with m.If(walking):
        m.d.sync += [unit.eq(Mux(beat_read, 0, unit + 1)),
                     last_unit.eq(Mux(beat_read, words == 1, unit + 1 == words - 1))]
        with m.Switch(state):
            with m.Case(_STAMP):
                m.d.sync += state.eq(_STAMP_NS)
            with m.Case(_STAMP_NS):
                m.d.sync += state.eq(_FRAME_LEN)
            with m.Case(_FRAME_LEN):  # words of the string (none only for a length of zero)
                m.d.sync += [remaining.eq((word + 3) >> 2), state.eq(Mux(word_zero, _HEIGHT, _FRAME))]
            with m.Case(_ENC_LEN):  # the encoding's words hold is_bigendian too
                m.d.sync += [remaining.eq((word + 4) >> 2), state.eq(_ENC)]
            with m.Case(_FRAME, _ENC):
                m.d.sync += remaining.eq(remaining - 1)
                with m.If(remaining <= 1):
                    m.d.sync += state.eq(Mux(state == _FRAME, _HEIGHT, _STEP))
            with m.Case(_HEIGHT):
                m.d.sync += state.eq(_WIDTH)
            with m.Case(_WIDTH):
                m.d.sync += state.eq(_ENC_LEN)
            with m.Case(_STEP):
                m.d.sync += [step.eq(word), state.eq(_DATA_LEN), at_data_len.eq(1)]
            with m.Case(_DATA_LEN):
                m.d.sync += [data_len.eq(word), state.eq(Mux(word_zero, _STAMP, _DATA)),
                             at_data_len.eq(0),
                             start.eq(Mux(pixels_here, (unit + 1) << 2, 0))]
                due = Signal(bits)
                m.d.comb += due.eq((step >> _log2(lanes)) + _LAG)
                m.d.sync += [until_window.eq(due), window_due.eq(due == 0)]
    for walk, copy_pixels in zip(walks, pixel_copies, strict=True):
        with m.If(walk & at_data_len):
            m.d.sync += copy_pixels.eq(~word_zero)
    # a message that ends in its header (no pixels): the walk starts over a cycle later, from a register
    # (not from the decision that let the beat go), and picks no word meanwhile
    m.d.sync += header_ended.eq(header_leaves & hold_last)
    with m.If(header_ended):
        m.d.sync += [state.eq(_STAMP), unit.eq(0), *(first.eq(1) for first in firsts), last_unit.eq(words == 1),
                     phase.eq(0), at_data_len.eq(0)]

    # --- the pixels: a step per beat, through two rings of beats -----------------------------------------
    pipe = Pipe(m)
    shift = _log2(lanes)
    lines = Signal(bits)  # beats a line (the node refuses images whose step is not whole beats)
    m.d.comb += lines.eq(step >> shift)
    ring_bits = max(1, (depth - 1).bit_length())
    pointer = Signal(ring_bits)
    # a wide ring in distributed RAM is hundreds of cells on one pointer (23.9 ns of routing at 512 bits):
    # block RAM takes a ring of 512 bits in 15 blocks
    style = {"ram_style": "block"} if data_width >= _BLOCK_RAM_RINGS else None
    rings = [Memory(shape=unsigned(data_width), depth=depth, init=[], attrs=style) for _ in range(2)]
    m.submodules.ring_older, m.submodules.ring_newer = rings
    writes = [r.write_port() for r in rings]
    reads = [r.read_port(domain="sync") for r in rings]  # read-first: a ring gives the beat it replaces
    stepping = Signal()
    flush_copies = [Signal(name=f"flushing{copy}") for copy in range(copies)]  # as ``pixel_copies``
    flushing = flush_copies[0]
    final_flush = Signal()  # flush_left == 1, as a register
    flush_left = Signal(bits)
    real_beats = Signal(24)  # pixel beats stepped in this message
    owed_copies = [Signal(name=f"owed_last{copy}") for copy in range(copies)]  # the message's last beat has stepped
    owed_last = owed_copies[0]
    last_keep = Signal(lanes)
    windows = Signal()  # every step after the first that fills a window fills one
    centre = Signal(24)  # the pixel beat whose window the registers hold
    # the beats the flush steps in (below the last line) are whatever the input holds: a window that reaches
    # them is on the frame's border, which the masks below give as 0 or as it came
    incoming = hold
    ring_step = Signal()
    m.d.comb += [reads[0].addr.eq(pointer), reads[1].addr.eq(pointer), reads[0].en.eq(ring_step),
                 reads[1].en.eq(ring_step), writes[0].addr.eq(pointer), writes[1].addr.eq(pointer),
                 writes[0].data.eq(incoming), writes[1].data.eq(reads[0].data),
                 writes[0].en.eq(ring_step), writes[1].en.eq(ring_step)]
    # the bottom row (a), the middle (b) and the top (c): after step n, a[k] is beat n - k of the stream
    a = [Signal(data_width, name=f"a{i}") for i in range(5)]
    b = [Signal(data_width, name=f"b{i}") for i in range(5)]
    c = [Signal(data_width, name=f"c{i}") for i in range(4)]
    # the registers hold a window the pipeline has not taken yet, a copy each (the valid at the pipeline's end
    # then chooses a FIFO's input and enables it from a register by that FIFO's slice)
    fresh_copies = [Signal(name=f"window_fresh{copy}") for copy in range(copies)]
    first_window = ~windows & window_due
    later_window = windows
    steps = [Signal(name=f"stepping{copy}") for copy in range(copies)]
    for copy_step, held, copy_room, copy_pixels, copy_flushing, copy_owed, fresh in zip(
            steps, held_copies, rooms, pixel_copies, flush_copies, owed_copies, fresh_copies, strict=True):
        m.d.comb += copy_step.eq(copy_pixels & (copy_flushing | held & ~copy_owed) & copy_room)
        m.d.sync += fresh.eq(copy_step & (first_window | later_window))
        with m.If(copy_step & ~copy_flushing & hold_last):
            m.d.sync += [copy_flushing.eq(1), copy_owed.eq(1)]
        with m.If(copy_step & copy_flushing & final_flush):
            m.d.sync += copy_flushing.eq(0)
    m.d.comb += stepping.eq(steps[0])
    for index, copy_step in enumerate(steps[2:]):
        bits_of = slice(index * slice_bits, (index + 1) * slice_bits)
        with m.If(copy_step):
            m.d.sync += [a[0][bits_of].eq(incoming[bits_of]), *(a[k + 1][bits_of].eq(a[k][bits_of]) for k in range(4)),
                         b[1][bits_of].eq(reads[0].data[bits_of]),
                         *(b[k + 1][bits_of].eq(b[k][bits_of]) for k in range(1, 4)),
                         c[1][bits_of].eq(reads[1].data[bits_of]),
                         *(c[k + 1][bits_of].eq(c[k][bits_of]) for k in range(1, 3))]
    m.d.comb += ring_step.eq(steps[1])
    with m.If(ring_step):
        m.d.sync += pointer.eq(Mux(pointer + 1 >= lines, 0, pointer + 1))
    with m.If(stepping):
        with m.If(~window_due):
            m.d.sync += [until_window.eq(until_window - 1), window_due.eq(until_window == 1)]
        with m.If(first_window):
            m.d.sync += [centre.eq(0), windows.eq(1)]
        with m.Elif(later_window):
            m.d.sync += centre.eq(centre + 1)
        with m.If(~flushing):
            m.d.sync += real_beats.eq(real_beats + 1)
            with m.If(hold_last):
                m.d.sync += [flush_left.eq(lines + _LAG), final_flush.eq(lines + _LAG == 1),
                             last_keep.eq(hold_keep)]
        with m.Else():
            m.d.sync += [flush_left.eq(flush_left - 1), final_flush.eq(flush_left == 2)]
    m.d.comb += release.eq(header_leaves | (stepping & ~flushing))
    # the window of the middle beat b[3]: rows c (top), b, a (bottom); beats [4] before, [3], [2] after (c one
    # index less: its ring is a step behind); every ring's output is registered before the kernels use it
    top_row, middle_row, bottom_row = (c[3], c[2], c[1]), (b[4], b[3], b[2]), (a[4], a[3], a[2])

    def lane_bytes(row: tuple[Value, Value, Value], lane: int) -> list[Value]:
        before, this, after = row
        picked = []
        for offset in (-channels, 0, channels):
            index = lane + offset
            beat = before if index < 0 else after if index >= lanes else this
            picked.append(beat.word_select(index % lanes, 8))
        return picked

    # where each lane of the middle beat sits, decided for the beat, not for each lane: a line is whole beats,
    # so the pixels' first byte ``start`` splits every beat at the same lane. Lanes from ``start`` on hold
    # this beat's bytes of a line (the n-th beat since the pixels began is beat n % lines of line n // lines);
    # lanes before it hold the end of the beat before (n - 1), the header's last bytes when n is 0. A lane
    # keeps only what ``start`` makes of it (which side of the split it is on, whether it is among the first
    # or the last ``channels`` bytes of its beat); the beat's side is a few flags, for this beat and the one
    # before. (A column and row a lane, compared with the line's length, were 64 carry chains on one bus at
    # 512 bits: a quarter of the congestion that kept the compensation from routing.) How many of the
    # message's pixel bytes lie beyond lane 0 gives the last row without the height (a memory node's
    # synthetic header has none).
    # They move a cycle after the step, from registers (``lane_first``, ``lane_later``), and the masks are a
    # stage shorter: from the step itself, the control's decision reached these registers, which the 64 lanes
    # pull across the device (the 512-bit compensation's critical path, 15.5 of 16.9 ns routing).
    lane_first, lane_later = Signal(), Signal()
    m.d.sync += [lane_first.eq(stepping & first_window), lane_later.eq(stepping & later_window)]
    beyond = Signal(signed(34))  # pixel bytes from lane 0 of the middle beat to the end
    below = Signal(signed(34))  # the same, less the last row
    # whether either count reaches past the beat, as a register a count, decided with the count: a test of its
    # 27 high bits that all lanes shared, one net from three logic levels to 64 lanes, was the 512-bit
    # compensation's critical path (11.6 of 13.7 ns routing)
    beyond_past, below_past = Signal(), Signal()
    next_beyond, next_below = Signal(signed(34)), Signal(signed(34))
    m.d.comb += [next_beyond.eq(Mux(lane_first, data_len + start, beyond - lanes)),
                 next_below.eq(Mux(lane_first, data_len + start - step, below - lanes))]
    with m.If(lane_first | lane_later):
        m.d.sync += [beyond.eq(next_beyond), below.eq(next_below),
                     beyond_past.eq(next_beyond[shift:-1] != 0), below_past.eq(next_below[shift:-1] != 0)]
    beat_of_line = Signal(bits)  # n % lines
    one_beat_lines = Signal()  # lines == 1, as a register (the line's length is known long before its pixels)
    m.d.sync += one_beat_lines.eq(lines == 1)
    this = _BeatPlace("this")  # beat n
    before = _BeatPlace("before")  # beat n - 1
    header_before = Signal()  # n is 0: the lanes before ``start`` hold header bytes
    with m.If(lane_first):
        m.d.sync += [beat_of_line.eq(0), this.first.eq(1), this.last.eq(one_beat_lines), this.later_line.eq(0),
                     header_before.eq(1), before.first.eq(0), before.last.eq(0), before.later_line.eq(0)]
    with m.Elif(lane_later):
        m.d.sync += [before.first.eq(this.first), before.last.eq(this.last), before.later_line.eq(this.later_line),
                     header_before.eq(0), this.first.eq(this.last), this.later_line.eq(this.later_line | this.last)]
        with m.If(this.last):
            m.d.sync += [beat_of_line.eq(0), this.last.eq(one_beat_lines)]
        with m.Else():
            m.d.sync += [beat_of_line.eq(beat_of_line + 1), this.last.eq(beat_of_line + 2 == lines)]
    interior, pixel, header = [], [], []
    for lane in range(lanes):
        # what ``start`` makes of this lane, as registers: ``start`` is set in the header, beats before the pixels
        after_split = Signal(name=f"after_split{lane}", init=1)
        leading, trailing = Signal(name=f"leading{lane}"), Signal(name=f"trailing{lane}")
        offset = (Const(lane, shift + 1) - start)[:shift]  # the lane's byte in its beat of a line
        m.d.sync += [after_split.eq(start <= lane if lane < lanes - 1 else Const(1, 1)),
                     leading.eq(offset < channels if channels < lanes else Const(1, 1)),
                     trailing.eq(offset >= lanes - channels if channels < lanes else Const(1, 1))]
        first, last, later_line = (Mux(after_split, mine, theirs) for mine, theirs in
                                   ((this.first, before.first), (this.last, before.last),
                                    (this.later_line, before.later_line)))
        at_edge = (leading & first) | (trailing & last)
        is_header = ~after_split & header_before
        interior.append(later_line & _exceeds(below, below_past, lane, shift) & ~at_edge)
        pixel.append(~is_header & _exceeds(beyond, beyond_past, lane, shift))
        header.append(is_header)
    last_centre = owed_last & (centre + 1 == real_beats)

    # the kernel, lane by lane, then the node's own stages after it
    # the valid, a chain a copy; lane i's is its slice's
    valids = [[fresh] for fresh in fresh_copies]
    lane_copy = [2 + lane * 8 // slice_bits for lane in range(lanes)]
    kernels = [node.lane_kernel(pipe, lane_bytes(top_row, lane), lane_bytes(middle_row, lane),
                                lane_bytes(bottom_row, lane)) for lane in range(lanes)]
    stages = node.kernel_stages
    masks = [pipe.delay(Cat(interior[i], pixel[i], header[i]), stages - 1, f"mask{i}") for i in range(lanes)]
    raw = pipe.delay(b[3], stages, "raw")
    last_flag = pipe.delay(last_centre, stages, "last")
    for chain in valids:
        for _ in range(stages):
            chain.append(pipe.reg(chain[-1], "valid"))
    shaped = [Mux(masks[i][0], kernels[i], 0)[:8] for i in range(lanes)]
    node.observe_lanes(m, shaped, [masks[i][1] for i in range(lanes)], [valids[lane_copy[i]][-1] for i in range(lanes)],
                       data_len)
    posted = node.post_lanes(m, pipe, shaped)
    after = node.post_stages
    masks = [pipe.delay(mask, after, f"postmask{i}") for i, mask in enumerate(masks)]
    raw = pipe.delay(raw, after, "postraw")
    last_flag = pipe.delay(last_flag, after, "postlast")
    for chain in valids:
        for _ in range(after):
            chain.append(pipe.reg(chain[-1], "postvalid"))
    out_bytes = [Mux(masks[i][2], raw.word_select(i, 8), Mux(masks[i][1], posted[i], 0)) for i in range(lanes)]
    m.d.comb += reserved.eq(header_leaves | (stepping & (first_window | later_window)))
    # a beat of header goes into the FIFO a cycle after the walk let it go, from a copy of the held beat that
    # every cycle takes (no enable): the choice between it and the pipeline's beat, made for each of the
    # FIFO's hundreds of input bits, then comes from a register. Made from the walk's decision, it was the
    # 512-bit compensation's critical path (8.5 ns of its 18.3 ns routing that one net). The credit is
    # counted from the decision, so the FIFO has room for it; header beats and the pipeline's never meet
    # (the walk starts once the frame before has left).
    # Each FIFO makes that choice from a copy of its own of the push (and of the valid), decided from the walk
    # of the copy that loads its slice: one register choosing for all 577 bits was the next critical path.
    header_beat, header_keep, header_last = Signal(data_width), Signal(lanes), Signal()
    m.d.sync += [header_beat.eq(hold), header_keep.eq(hold_keep), header_last.eq(hold_last)]
    header_pushes = [Signal(name=f"header_push{copy}") for copy in range(copies)]
    m.d.sync += [push.eq(walk & beat_read & ~pixels_here) for push, walk in zip(header_pushes, walks, strict=True)]
    header_entry = Cat(header_beat, header_keep, header_last)
    pipeline_entry = Cat(*out_bytes, Mux(last_flag, last_keep, Const((1 << lanes) - 1, lanes)), last_flag)
    for index, part in enumerate(out_fifos):
        start = index * _FIFO_SLICE
        copy = 2 + start // slice_bits if start < data_width else (start - data_width) // _FIFO_SLICE % 2
        piece = slice(start, start + len(part.w_data))
        m.d.comb += [part.w_en.eq(header_pushes[copy] | valids[copy][-1]),
                     part.w_data.eq(Mux(header_pushes[copy], header_entry[piece], pipeline_entry[piece]))]
    ended = Signal()  # the frame's last beat went out last cycle: the walk starts over (from a register)
    m.d.sync += ended.eq(~header_pushes[0] & valids[0][-1] & last_flag)
    with m.If(ended):
        m.d.sync += [state.eq(_STAMP), unit.eq(0), *(first.eq(1) for first in firsts), last_unit.eq(words == 1),
                     windows.eq(0), real_beats.eq(0), pointer.eq(0), *(owed.eq(0) for owed in owed_copies),
                     *(copy_pixels.eq(0) for copy_pixels in pixel_copies)]
    waiting = Signal()
    m.d.comb += waiting.eq(node.between_frames_lanes(m, ended))
    m.d.comb += busy.eq(waiting)


def _input_pair(m: Module, source: Any, data_width: int, slices: int,
                copies: int) -> tuple[Value, Value, Value, list[Signal], Signal]:
    """Two input beats, written in turn by the stream and read in turn by the node: the held beat (read in
    ``slices``), its keep and last, ``copies`` copies of whether one is held (each counted on its own), and
    the node's signal that lets it go. Only the stream's side loads the beats (an entry's enable is its turn
    and room in the pair, from registers), and letting a beat go moves a pointer: a beat loaded on the node's
    decision (TREADY from the step through the pixels) put that decision on the enables of twice 512
    registers, the 512-bit compensation's critical path (17.8 ns). TREADY is a register, as a register
    slice's is."""
    lanes = data_width // 8
    entries = [(Signal(data_width, name=f"in{k}_data"), Signal(lanes, name=f"in{k}_keep"),
                Signal(name=f"in{k}_last")) for k in range(2)]
    release = Signal()
    held_copies, fulls, takings = [], [], []
    for copy in range(copies):
        held, after = Signal(2, name=f"held{copy}"), Signal(2, name=f"after{copy}")
        held_copies.append(Signal(name=f"hold_full{copy}"))
        fulls.append(Signal(name=f"full{copy}"))
        takings.append(Signal(name=f"taking{copy}"))
        m.d.comb += [takings[-1].eq(source.tvalid & ~fulls[-1]), after.eq(held + takings[-1] - release)]
        m.d.sync += [held.eq(after), held_copies[-1].eq(after != 0), fulls[-1].eq(after == 2)]
    m.d.comb += source.tready.eq(~fulls[0])
    # which entry is written and which is read, a copy a slice of the beat (toggles, which synthesis cannot
    # merge): one write turn enabling both entries' 1,154 flip-flops was the 512-bit blur's critical path
    # (9.8 ns of routing on that net), and one read turn selecting all 512 bits a net of 512 loads
    part = data_width // slices
    write_turns = [Signal(name=f"write_turn{index}") for index in range(slices)]
    read_turns = [Signal(name=f"read_turn{index}") for index in range(slices)]
    # An entry loads whenever it is the next to be written and the pair is not full (it then holds nothing),
    # whether TVALID is high or not: TVALID, a register of whatever is upstream, then moves only the turns and
    # counts, and each slice's enable comes from registers beside it (TVALID to the entries' enables was the
    # 512-bit compensation's critical path once the rest was pipelined, 12.4 ns of routing).
    for index, write_turn in enumerate(write_turns):
        with m.If(takings[index + 2]):
            m.d.sync += write_turn.eq(~write_turn)
    for turn, (data, keep, last) in enumerate(entries):
        with m.If(~fulls[0] & (write_turns[0] == turn)):
            m.d.sync += [keep.eq(source.tkeep), last.eq(source.tlast)]
        for index, write_turn in enumerate(write_turns):
            bits_of = slice(index * part, (index + 1) * part)
            with m.If(~fulls[index + 2] & (write_turn == turn)):
                m.d.sync += data[bits_of].eq(source.tdata[bits_of])
    with m.If(release):
        m.d.sync += [turn.eq(~turn) for turn in read_turns]
    (data0, keep0, last0), (data1, keep1, last1) = entries
    data = Cat(*(Mux(turn, data1[index * part:(index + 1) * part], data0[index * part:(index + 1) * part])
                 for index, turn in enumerate(read_turns)))
    return data, Mux(read_turns[0], keep1, keep0), Mux(read_turns[0], last1, last0), held_copies, release


class _BeatPlace:
    """Where a beat of the pixels sits in its line: its first beat, its last, in a line after the first."""

    def __init__(self, name: str) -> None:
        self.first = Signal(name=f"{name}_first")
        self.last = Signal(name=f"{name}_last")
        self.later_line = Signal(name=f"{name}_later_line")


def _exceeds(count: Value, past: Value, lane: int, shift: int) -> Value:
    """``count > lane`` for a lane of the beat (``lane < 2 ** shift``), from the count's low bits and sign and
    ``past``, whether its other high bits are not all zero, which the lanes share: a wide comparison a lane
    was a carry chain a lane."""
    if lane == (1 << shift) - 1:  # no low bits exceed the last lane (a comparison lint tools call constant)
        return ~count[-1] & past
    return ~count[-1] & (past | (count[:shift] > lane))


def _log2(value: int) -> int:
    if value < 4 or value & (value - 1):
        raise HardwareError(f"a full-width filter needs a power-of-two data_width of at least 32 bits, not "
                            f"{value * 8!r}: set the node's lanes parameter to 1 (a byte a cycle)")
    return value.bit_length() - 1


def low_middle_high(a: Value, b: Value, c: Value) -> tuple[Value, Value, Value]:
    """The lowest, the middle and the highest of three values, each chosen by the same three comparisons,
    made side by side: one comparison's delay, where compare-exchanges in series take three."""
    ab, ac, bc = a < b, a < c, b < c
    return (Mux(ab, Mux(ac, a, c), Mux(bc, b, c)),
            Mux(ab, Mux(bc, b, Mux(ac, c, a)), Mux(ac, a, Mux(bc, c, b))),
            Mux(ab, Mux(bc, c, b), Mux(ac, c, a)))
