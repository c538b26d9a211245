"""Streaming 3x3 image filters as hardware nodes: ``sensor_msgs/msg/Image`` in, the same out.

A mono8 image arrives as its CDR body (``_beats``), so a filter walks the message's fields
byte by byte: the header, frame_id, height, width, encoding, is_bigendian and step pass
through unchanged (the output image has the same shape and encoding), and the pixel bytes
go through two line buffers and a 3x3 window, one pixel a clock cycle. Output pixel ``o``
leaves when input pixel ``o + width + 1`` arrives (its whole window is in); after the last
pixel the remaining ``width + 1`` outputs (the bottom border) are flushed.

Border pixels (the outer rows and columns) are 0, in hardware and in the software twins
in ``hetros.hw.reference``, the bit-exact specification the tests hold the hardware to.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.hdl import Value
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..._errors import HardwareError
from ..streams._axi import axi_stream
from ..streams._bytes import bytes_in, bytes_out
from ..streams._ports import port_part
from ._lanes import Pipe, elaborate_lanes, low_middle_high

# bytes per pixel of the encodings whose pixels are bytes (sensor_msgs/image_encodings)
_BYTES_PER_PIXEL = {"mono8": 1, "8UC1": 1, "8SC1": 1, "rgb8": 3, "bgr8": 3, "8UC3": 3, "rgba8": 4, "bgra8": 4,
                    "8UC4": 4, "mono16": 2, "16UC1": 2}
# the byte walk over sensor_msgs/msg/Image's CDR body
_STAMP, _FRAME_LEN, _FRAME, _PAD1, _HEIGHT, _WIDTH, _ENC_LEN, _ENC, _BIGEND, _PAD2, _STEP, _DATA_LEN, _DATA = \
    range(13)


class ImageFilter3x3(wiring.Component):
    """An image filter over a 3x3 window of each channel (subclasses give :meth:`kernel`).

    ``width`` is the widest image line the line buffers hold and ``channels`` the bytes of a pixel
    (1 for mono8, 3 for rgb8), both elaboration parameters from the node's parameters; narrower
    images work unchanged, wider ones are not supported. A line is the image's ``step`` bytes.
    """

    #: register stages of :meth:`lane_kernel` and :meth:`post_lanes` (the full-width datapath delays the rest
    #: of a beat by as many)
    kernel_stages = 1
    post_stages = 0

    def __init__(self, source: str, sink: str, data_width: int = 64, width: int = 640, channels: int = 1,
                 lanes: int = 0) -> None:
        if width < 3:
            raise HardwareError(f"width must be at least 3 pixels, not {width!r}")
        if channels < 1:
            raise HardwareError(f"channels must be at least 1, not {channels!r}")
        full = data_width // 8
        if lanes == 0:
            lanes = full if full >= 4 and not full & (full - 1) else 1
        if lanes not in (1, full):
            raise HardwareError(f"lanes must be 1 (a byte a cycle) or {full} (a whole {data_width}-bit beat a cycle), "
                                f"not {lanes!r}")
        if lanes > 1 and channels > lanes:
            raise HardwareError(f"channels must be at most lanes ({lanes}) in a full-width filter, not {channels!r}: "
                                "set lanes to 1")
        self._source, self._sink = port_part(source), port_part(sink)
        self.data_width, self.width, self.channels, self.lanes = data_width, width, channels, lanes
        super().__init__({self._source: In(axi_stream(data_width)), self._sink: Out(axi_stream(data_width))})

    def check_message(self, topic: str, message: Any) -> None:
        """The images this node can filter, checked in software before one goes in (the gateway refuses
        the others, naming why): a line wider than the line buffers would wrap them and give wrong pixels,
        and a frame whose pixels do not match its header would be walked wrong."""
        height, width, step = int(message.height), int(message.width), int(message.step)
        size = len(message.data)
        encoding = str(message.encoding)
        pixel = _BYTES_PER_PIXEL.get(encoding)
        if pixel is not None and pixel != self.channels:
            raise HardwareError(f"a {encoding} image has {pixel}-byte pixels, but this node takes {self.channels}-byte "
                                "pixels (its channels parameter): set channels to match, or send "
                                f"{'mono8' if self.channels == 1 else 'rgb8'} images")
        if size != height * step:
            raise HardwareError(f"an image whose header says {height} rows of {step} bytes ({height * step} bytes) "
                                f"carries {size} bytes of pixels: fix the publisher (height, step and data must "
                                "agree)")
        if step < width * self.channels:
            raise HardwareError(f"an image {width} pixels wide has a step of {step} bytes, less than {width} x "
                                f"{self.channels} bytes a pixel: this node takes {self.channels}-byte pixels "
                                "(its channels parameter); fix the step or the node's channels")
        if step > self.width * self.channels:
            raise HardwareError(f"an image line of {step} bytes ({width} pixels) is wider than the node's line "
                                f"buffers ({self.width} pixels of {self.channels} bytes): set the node's width "
                                f"parameter to at least {-(-step // self.channels)}, or send narrower images")
        if height < 3 or width < 3:
            raise HardwareError(f"an image of {width}x{height} pixels is too small for a 3x3 window: send images of "
                                "at least 3x3")
        if step % self.lanes:
            raise HardwareError(f"an image line of {step} bytes is not a whole number of {self.lanes}-byte beats, "
                                f"which this full-width node takes a cycle each: send images whose step is a "
                                f"multiple of {self.lanes}, or set the node's lanes parameter to 1 (a byte a cycle, "
                                "any step)")

    def reference(self) -> Callable[[np.ndarray[Any, Any]], np.ndarray[Any, Any]] | None:
        """This filter in software, bit-exact (``hetros.hw.reference``): a function of an image array
        (rows x columns, or rows x columns x channels), None where a subclass has none."""
        return None

    def twin(self) -> Callable[[Any], Any] | None:
        """The node in software, message to message: what `hetros hw report --models` holds the hardware's
        output to. A fresh twin per stream of frames (a stateful filter keeps state between frames)."""
        reference = self.reference()
        if reference is None:
            return None
        channels = self.channels

        def filtered(message: Any) -> Any:
            shape = (int(message.height), int(message.width)) + ((channels,) if channels > 1 else ())
            pixels = np.asarray(message.data).reshape(int(message.height), int(message.step))
            image = pixels[:, :int(message.width) * channels].reshape(shape)
            out = message.copy()
            out.data = np.ascontiguousarray(reference(image)).reshape(-1)
            out.step = int(message.width) * channels
            return out

        return filtered

    def kernel(self, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        """The output pixel of a window (rows top to bottom, each column left to right), 8 bits."""
        raise NotImplementedError

    def lane_kernel(self, pipe: Pipe, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        """:meth:`kernel` in the full-width datapath, with ``kernel_stages`` registers (``pipe.reg``) on its way
        so that it meets the clock; here one, after the whole kernel."""
        return pipe.reg(self.kernel(top, middle, bottom), "kernel")

    def post_lanes(self, m: Module, pipe: Pipe, values: list[Value]) -> list[Value]:
        """:meth:`post` of each lane's byte, with ``post_stages`` registers; here none."""
        return [self.post(m, value) for value in values]

    def observe_lanes(self, m: Module, values: list[Value], pixels: list[Value], taken: list[Value],
                      count: Value) -> None:
        """:meth:`observe` for a beat: ``values`` before :meth:`post_lanes`, ``pixels`` high in the lanes that are
        the image's (the others are header bytes or past its end), ``taken[i]`` when lane i's byte moves on (the
        same for every lane, a copy by each slice of the beat) and ``count`` the image's bytes. Nothing here."""

    def between_frames_lanes(self, m: Module, ended: Value) -> Value:
        """:meth:`between_frames` of the full-width datapath; nothing here."""
        return Const(0, 1)

    def post(self, m: Module, value: Value) -> Value:
        """What an output byte becomes after the window (its border zeros included): itself here."""
        return value

    def observe(self, m: Module, value: Value, taken: Value) -> None:
        """See each output byte before :meth:`post` (``taken`` high when it leaves); nothing here."""

    def between_frames(self, m: Module, ended: Value) -> Value:
        """Work between two messages: ``ended`` strobes when one has left; while the returned value is
        high, the next message waits. Nothing here."""
        return Const(0, 1)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        source = getattr(self, self._source)
        sink = getattr(self, self._sink)
        if self.lanes > 1:
            elaborate_lanes(self, m, source, sink, self.data_width)
            return m

        incoming = bytes_in(m, source, self.data_width)
        byte, byte_valid, byte_last, take = incoming.byte, incoming.valid, incoming.last, incoming.take
        outgoing = bytes_out(m, sink, self.data_width)
        out_valid, out_byte, out_last, out_ready = outgoing.valid, outgoing.byte, outgoing.last, outgoing.ready

        # the field walk
        state = Signal(range(13))
        position = Signal(32)  # of the byte being taken, in the message
        word = Signal(32)
        word_byte = Signal(2)
        remaining = Signal(32)
        line = Signal(32)
        column = Signal(32)
        row = Signal(32)
        received = Signal(32)
        emitted = Signal(32)
        flushing = Signal()
        new_word = Cat(word[8:], byte)  # the little-endian word once this byte is in
        word_done = word_byte == 3
        aligned_next = (position + 1)[:2] == 0

        # line buffers: rows r-2 and r-1 at the current column (a column is a byte of a pixel)
        depth = self.width * self.channels
        buffers = [Memory(shape=unsigned(8), depth=depth, init=[]) for _ in range(2)]
        m.submodules.line_older, m.submodules.line_newer = buffers
        writes = [b.write_port() for b in buffers]
        # synchronous reads (block RAM), one cycle ahead: each cycle reads the column the next image byte
        # will have, so its two line-buffer bytes are there when it is taken
        reads = [b.read_port(domain="sync", transparent_for=(w,)) for b, w in zip(buffers, writes, strict=True)]
        pixel = (state == _DATA) & byte_valid & ~flushing
        bits = max(1, (depth - 1).bit_length())
        following = Mux(column == line - 1, 0, column + 1)
        upcoming = Mux(state == _DATA, Mux(pixel & take, following, column), 0)
        address = column[:bits]
        m.d.comb += [reads[0].addr.eq(upcoming[:bits]), reads[1].addr.eq(upcoming[:bits]),
                     writes[0].addr.eq(address), writes[1].addr.eq(address), writes[0].data.eq(reads[1].data),
                     writes[1].data.eq(byte), writes[0].en.eq(pixel & take), writes[1].en.eq(pixel & take)]
        # the bytes of the last two pixels of each row, oldest first: columns c-2 and c-1 of this channel
        channels = self.channels
        left = [[Signal(8, name=f"w{r}_{c}") for c in range(2 * channels)] for r in range(3)]
        newest = [reads[0].data, reads[1].data, byte]
        window = [[left[r][0], left[r][channels], newest[r]] for r in range(3)]
        filtered = Signal(8)
        m.d.comb += filtered.eq(self.kernel(*window))
        interior = (row >= 2) & (column >= 2 * channels)
        # this byte completes the window of output ``received - line - channels``
        lagging = received >= line + channels
        before_post = Signal(8)
        leaving = Signal()  # an image byte leaves this cycle (for ``observe``)
        ended = Signal()  # the message's last byte leaves this cycle
        waiting = Signal()
        self.observe(m, before_post, leaving)
        m.d.comb += waiting.eq(self.between_frames(m, ended))
        posted = Signal(8)
        m.d.comb += posted.eq(self.post(m, before_post))

        with m.If(flushing):
            m.d.comb += [out_valid.eq(1), before_post.eq(0), out_byte.eq(posted),
                         out_last.eq(received - emitted == 1), leaving.eq(out_ready),
                         ended.eq(out_ready & (received - emitted == 1))]
            with m.If(out_ready):
                m.d.sync += emitted.eq(emitted + 1)
                with m.If(received - emitted == 1):
                    m.d.sync += [flushing.eq(0), state.eq(_STAMP), position.eq(0), word_byte.eq(0)]
        with m.Elif(byte_valid & ~(waiting & (state == _STAMP) & (position == 0))):
            emits = Signal()
            with m.If(state == _DATA):
                m.d.comb += [emits.eq(lagging), before_post.eq(Mux(interior, filtered, 0)),
                             out_byte.eq(posted),
                             out_last.eq(byte_last & (received + 1 - emitted == 1)), leaving.eq(lagging & out_ready)]
            with m.Else():
                m.d.comb += [emits.eq(1), out_byte.eq(byte), out_last.eq(byte_last)]
            m.d.comb += [out_valid.eq(emits), take.eq(~emits | out_ready)]
            with m.If(byte_last & take):
                m.d.comb += ended.eq(~((state == _DATA) & (received + 1 - emitted - lagging != 0)))
        with m.If(take):
            m.d.sync += [position.eq(position + 1), word.eq(new_word), word_byte.eq(word_byte + 1)]
            with m.Switch(state):
                with m.Case(_STAMP):
                    with m.If(position == 7):
                        m.d.sync += [state.eq(_FRAME_LEN), word_byte.eq(0)]
                with m.Case(_FRAME_LEN):
                    with m.If(word_done):
                        m.d.sync += [remaining.eq(new_word), state.eq(_FRAME)]
                with m.Case(_FRAME, _ENC):
                    m.d.sync += remaining.eq(remaining - 1)
                    with m.If(remaining == 1):
                        m.d.sync += [state.eq(Mux(aligned_next, Mux(state == _FRAME, _HEIGHT, _BIGEND),
                                                  Mux(state == _FRAME, _PAD1, _BIGEND))), word_byte.eq(0)]
                with m.Case(_PAD1):
                    with m.If(aligned_next):
                        m.d.sync += [state.eq(_HEIGHT), word_byte.eq(0)]
                with m.Case(_HEIGHT):
                    with m.If(word_done):
                        m.d.sync += state.eq(_WIDTH)
                with m.Case(_WIDTH):
                    with m.If(word_done):
                        m.d.sync += state.eq(_ENC_LEN)
                with m.Case(_ENC_LEN):
                    with m.If(word_done):
                        m.d.sync += [remaining.eq(new_word), state.eq(_ENC)]
                with m.Case(_BIGEND):
                    m.d.sync += [state.eq(Mux(aligned_next, _STEP, _PAD2)), word_byte.eq(0)]
                with m.Case(_PAD2):
                    with m.If(aligned_next):
                        m.d.sync += [state.eq(_STEP), word_byte.eq(0)]
                with m.Case(_STEP):
                    with m.If(word_done):
                        m.d.sync += [line.eq(new_word), state.eq(_DATA_LEN)]
                with m.Case(_DATA_LEN):
                    with m.If(word_done):
                        m.d.sync += [remaining.eq(new_word), state.eq(_DATA), column.eq(0), row.eq(0),
                                     received.eq(0), emitted.eq(0)]
                with m.Case(_DATA):
                    m.d.sync += [received.eq(received + 1), remaining.eq(remaining - 1)]
                    for r in range(3):
                        m.d.sync += [left[r][k].eq(left[r][k + 1]) for k in range(2 * channels - 1)]
                        m.d.sync += left[r][-1].eq(newest[r])
                    with m.If(column == line - 1):
                        m.d.sync += [column.eq(0), row.eq(row + 1)]
                    with m.Else():
                        m.d.sync += column.eq(column + 1)
                    with m.If(lagging):
                        m.d.sync += emitted.eq(emitted + 1)
            with m.If(byte_last):
                # the message ends: outputs still owed (the bottom border) are flushed, then a new one starts
                owed = received + (state == _DATA) - emitted - ((state == _DATA) & lagging)
                with m.If((state == _DATA) & (owed != 0)):
                    m.d.sync += flushing.eq(1)
                with m.Else():
                    m.d.sync += [state.eq(_STAMP), position.eq(0), word_byte.eq(0)]
        return m


def _row_sum(row: list[Value]) -> Value:
    """``a + 2b + c``: one row (or column) of the Sobel and Gaussian kernels."""
    return row[0] + (row[1] << 1) + row[2]


def _column_sum(pipe: Pipe, column: list[Value]) -> Value:
    """``_row_sum`` of a window's column, a stage later (the lanes that share the column share this)."""
    return pipe.shared("column sum", column, lambda: pipe.reg(_row_sum(column), "column"))


def _widened(value: Value) -> Value:
    """An unsigned sum as a signed value of one more bit, so differences keep their sign."""
    return Cat(value, Const(0, 1)).as_signed()


class Sobel(ImageFilter3x3):
    """Edges: ``min(|Gx| + |Gy|, 255)`` with the 3x3 Sobel kernels (``hetros.hw.reference.sobel`` in software)."""

    def reference(self) -> Callable[[np.ndarray[Any, Any]], np.ndarray[Any, Any]] | None:
        from ..reference import sobel

        return sobel

    def kernel(self, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        right, left = [top[2], middle[2], bottom[2]], [top[0], middle[0], bottom[0]]
        gx = _widened(_row_sum(right)) - _widened(_row_sum(left))
        gy = _widened(_row_sum(bottom)) - _widened(_row_sum(top))
        magnitude = Mux(gx < 0, -gx, gx) + Mux(gy < 0, -gy, gy)
        return Mux(magnitude > 255, 255, magnitude)[:8]

    kernel_stages = 4

    def lane_kernel(self, pipe: Pipe, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        right, left = [top[2], middle[2], bottom[2]], [top[0], middle[0], bottom[0]]
        sums = [pipe.reg(_row_sum(row), "sum") for row in (right, left, bottom, top)]
        gx = pipe.reg(_widened(sums[0]) - _widened(sums[1]), "gx")
        gy = pipe.reg(_widened(sums[2]) - _widened(sums[3]), "gy")
        sizes = [pipe.reg(Mux(g < 0, -g, g)[:11], "size") for g in (gx, gy)]
        magnitude = sizes[0] + sizes[1]
        return pipe.reg(Mux(magnitude > 255, 255, magnitude)[:8], "sobel")


class GaussianBlur(ImageFilter3x3):
    """3x3 Gaussian ``[1 2 1; 2 4 2; 1 2 1] / 16``, rounded half up (in software:
    ``hetros.hw.reference.gaussian_blur``)."""

    def reference(self) -> Callable[[np.ndarray[Any, Any]], np.ndarray[Any, Any]] | None:
        from ..reference import gaussian_blur

        return gaussian_blur

    def kernel(self, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        total = _row_sum(top) + (_row_sum(middle) << 1) + _row_sum(bottom) + 8
        return (total >> 4)[:8]

    kernel_stages = 2

    def lane_kernel(self, pipe: Pipe, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        columns = [_column_sum(pipe, [top[i], middle[i], bottom[i]]) for i in range(3)]
        total = columns[0] + (columns[1] << 1) + columns[2] + 8
        return pipe.reg((total >> 4)[:8], "blur")


_HISTOGRAM_BITS = 24  # a lane's count of one value: 16 M bytes, a 4K rgb8 frame is 3.1 M a lane

# Paeth's 19 compare-exchanges that leave the median of nine in position 4: the first nine sort each triple,
# the last ten take the median of three sorted triples (lows at 0, 3, 6; middles 1, 4, 7; highs 2, 5, 8)
_MEDIAN9 = ((1, 2), (4, 5), (7, 8), (0, 1), (3, 4), (6, 7), (1, 2), (4, 5), (7, 8), (0, 3), (5, 8), (4, 7),
            (3, 6), (1, 4), (2, 5), (4, 7), (4, 2), (6, 4), (4, 2))


class Compensation(ImageFilter3x3):
    """The lane-following vehicle's image compensation: outliers out with a 3x3 median of each channel,
    then a contrast stretch between the 1st and 99th percentile of the previous frame's median image
    (its histogram is counted as the frame streams by and read between frames, so no frame buffer is
    needed; the first frame is not stretched). ``hetros.hw.reference.Compensation`` in software."""

    def reference(self) -> Callable[[np.ndarray[Any, Any]], np.ndarray[Any, Any]] | None:
        from ..reference import Compensation as Twin

        return Twin()

    def kernel(self, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        values = [*top, *middle, *bottom]
        for a, b in _MEDIAN9:
            values[a], values[b] = Mux(values[a] < values[b], values[a], values[b]), \
                Mux(values[a] < values[b], values[b], values[a])
        return values[4]

    # The median of nine is the median of the highest of the three columns' lows, the median of their
    # middles and the lowest of their highs, once each column is sorted. A lane's window shares its byte
    # columns with the lanes a pixel to each side, so each column of the beat is sorted once. Each of the
    # three stages is one level of comparisons side by side and a choice by their outcomes: Paeth's compare-
    # exchanges, two in series a stage, were the 512-bit compensation's critical path (11 logic levels,
    # 16.2 ns).
    kernel_stages = 3
    post_stages = 2

    def lane_kernel(self, pipe: Pipe, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        columns = [self._sorted_column(pipe, [top[i], middle[i], bottom[i]]) for i in range(3)]
        lows, middles, highs = zip(*columns, strict=True)
        candidates = (pipe.reg(low_middle_high(*lows)[2], "lows"), pipe.reg(low_middle_high(*middles)[1], "middles"),
                      pipe.reg(low_middle_high(*highs)[0], "highs"))
        return pipe.reg(low_middle_high(*candidates)[1], "median")

    @staticmethod
    def _sorted_column(pipe: Pipe, column: list[Value]) -> list[Value]:
        """``column`` low to high, a stage later (the lanes that share it share this)."""
        return pipe.shared("sorted column", column,
                           lambda: [pipe.reg(v, "column") for v in low_middle_high(*column)])

    def post_lanes(self, m: Module, pipe: Pipe, values: list[Value]) -> list[Value]:
        """Each lane's stretched byte: the table half of the word its histogram read gave (read, then held:
        the ``post_stages``), as the byte's value addressed both."""
        return [held[_HISTOGRAM_BITS:] for held in self._bins_held]

    def observe_lanes(self, m: Module, values: list[Value], pixels: list[Value], taken: list[Value],
                      count: Value) -> None:
        """A histogram per lane, each counting a byte a cycle with a read-modify-write four cycles long (the
        memory's output registered, then incremented, then written): the counts of the three bytes before,
        still on their way to the memory, are forwarded to a read of the same bin.

        A bin's word holds the lane's copy of the stretch table's entry for the same value beside the count
        (the byte addresses both in the same cycle), so a lane is one block RAM, not two: at 512 bits the
        two made 128 blocks of 208 and a design nextpnr did not route. The count's write-back carries the
        entry it read; between frames the scan clears the words and the table is written into them again."""
        self._count_lanes = count
        self._scanning_lanes, self._building_lanes = Signal(), Signal()
        self._level = Signal(9)
        self._table_address, self._table_entry, self._table_write = Signal(8), Signal(8), Signal()
        self._bins_held: list[Signal] = []
        # the scan's clearing writes and the table's, the same for every lane, come a cycle late from registers:
        # chosen in each lane from the state machine's logic, that choice was one net to every lane's memory
        # across the device (12 ns of routing at 512 bits, the critical path once the design routed)
        scanning, level = self._scanning_lanes, self._level
        by_level = Signal()  # a clearing or table write is due in every lane
        level_address, level_data, level_write = Signal(8), Signal(_HISTOGRAM_BITS + 8), Signal()
        m.d.sync += [by_level.eq(scanning | self._building_lanes),
                     level_address.eq(Mux(scanning, level[:8], self._table_address)),
                     level_data.eq(Mux(scanning, 0, Cat(Const(0, _HISTOGRAM_BITS), self._table_entry))),
                     level_write.eq(Mux(scanning, level < 256, self._building_lanes & self._table_write))]
        for lane, (value, is_pixel, lane_taken) in enumerate(zip(values, pixels, taken, strict=True)):
            histogram = Memory(shape=unsigned(_HISTOGRAM_BITS + 8), depth=256,
                               init=[entry << _HISTOGRAM_BITS for entry in range(256)])  # the first frame: as it is
            m.submodules[f"histogram{lane}"] = histogram
            read, write = histogram.read_port(domain="sync"), histogram.write_port()
            read_held = Signal(_HISTOGRAM_BITS + 8, name=f"read_held{lane}")
            m.d.sync += read_held.eq(read.data)
            self._bins_held.append(read_held)
            entry_held = Signal(8, name=f"entry{lane}")  # the stretch entry of the bin being counted, written back
            m.d.sync += entry_held.eq(read_held[_HISTOGRAM_BITS:])
            # (event, bin) of the byte in each cycle of its way: just taken, read back, counted, written
            events = [Signal(name=f"event{lane}_{k}") for k in range(5)]
            bins = [Signal(8, name=f"bin{lane}_{k}") for k in range(5)]
            m.d.comb += [events[0].eq(lane_taken & is_pixel), bins[0].eq(value)]
            m.d.sync += [e.eq(events[k]) for k, e in enumerate(events[1:])]
            m.d.sync += [b.eq(bins[k]) for k, b in enumerate(bins[1:])]
            # while read back, whether the 1st, 2nd, 3rd byte before it counted the same bin
            same = [Signal(name=f"same{lane}_{k}") for k in range(3)]
            m.d.sync += [flag.eq(events[k + 2] & (bins[k + 2] == bins[1])) for k, flag in enumerate(same)]
            counted = [Signal(_HISTOGRAM_BITS, name=f"counted{lane}_{k}") for k in range(3)]  # newest first
            latest = Mux(same[0], counted[0], Mux(same[1], counted[1], Mux(same[2], counted[2],
                                                                              read_held[:_HISTOGRAM_BITS])))
            m.d.sync += [counted[0].eq(latest + 1), counted[1].eq(counted[0]), counted[2].eq(counted[1])]
            m.d.comb += read.addr.eq(Mux(scanning, level[:8], value))
            with m.If(by_level):
                m.d.comb += [write.addr.eq(level_address), write.data.eq(level_data), write.en.eq(level_write)]
            with m.Else():
                m.d.comb += [write.addr.eq(bins[3]), write.data.eq(Cat(counted[0], entry_held)),
                             write.en.eq(events[3])]

    def between_frames_lanes(self, m: Module, ended: Value) -> Value:
        """Between two frames: wait for the last counts to land, sum the lanes' histograms bin by bin into
        the percentiles (each bin cleared behind), then rebuild the stretch table, a division of a value
        at a time by repeated subtraction (at most 511 steps: the quotient stops at 255)."""
        settle = Signal(range(6))
        scanning, building = self._scanning_lanes, self._building_lanes
        level = self._level
        # the scan's pipeline, a bin a cycle: the lanes' counts read, held, summed in pairs, summed four at a
        # time a stage until one is left (one stage up to eight lanes, three at 64), added to the running
        # total, multiplied by 100 (two stages), compared; ``stage[k]`` says which bin stage k holds
        reads = [held[:_HISTOGRAM_BITS] for held in self._bins_held]  # the counts, without the stretch entries
        pairs = [Signal(_HISTOGRAM_BITS + 1, name=f"pair{i}") for i in range(-(-len(reads) // 2))]
        sums = [pairs]
        while len(sums[-1]) > 1 or len(sums) == 1:
            sums.append([Signal(32, name=f"sum{len(sums)}_{i}") for i in range(-(-len(sums[-1]) // 4))])
        extra = len(sums) - 2  # tree stages past the one a pair-and-sum scan has
        stage = [(Signal(name=f"scan_valid{k}"), Signal(8, name=f"scan_level{k}")) for k in range(7 + extra)]
        (summed,) = sums[-1]
        running, hundred = Signal(34), Signal(41)
        sixty_four_and_thirty_two, four = Signal(41), Signal(41)
        low, high, found_low, found_high = Signal(8), Signal(8), Signal(), Signal()
        ninety_nine, ninety_six, three = Signal(41), Signal(41), Signal(41)  # 99 x count, in two adds too
        m.d.sync += [ninety_six.eq((self._count_lanes << 6) + (self._count_lanes << 5)),
                     three.eq((self._count_lanes << 1) + self._count_lanes), ninety_nine.eq(ninety_six + three)]
        with m.If(ended):
            m.d.sync += [settle.eq(5), running.eq(0), found_low.eq(0), found_high.eq(0)]
        with m.Elif(settle != 0):
            m.d.sync += settle.eq(settle - 1)
            with m.If(settle == 1):
                m.d.sync += [scanning.eq(1), level.eq(0)]
        with m.If(scanning):
            m.d.sync += [level.eq(level + 1), stage[0][0].eq(level < 256), stage[0][1].eq(level[:8])]
            m.d.sync += [stage[k + 1][0].eq(stage[k][0]) for k in range(len(stage) - 1)]
            m.d.sync += [stage[k + 1][1].eq(stage[k][1]) for k in range(len(stage) - 1)]
            m.d.sync += [pair.eq(reads[2 * i] + (reads[2 * i + 1] if 2 * i + 1 < len(reads) else 0))
                         for i, pair in enumerate(pairs)]
            for below, above in itertools.pairwise(sums):
                m.d.sync += [total.eq(sum(below[4 * i:4 * i + 4])) for i, total in enumerate(above)]
            with m.If(stage[3 + extra][0]):
                m.d.sync += running.eq(running + summed)
            # 100 x running in two adds, each a stage of its own (one 48-bit product missed the clock)
            m.d.sync += [sixty_four_and_thirty_two.eq((running << 6) + (running << 5)), four.eq(running << 2),
                         hundred.eq(sixty_four_and_thirty_two + four)]
            with m.If(stage[-1][0]):
                with m.If(~found_low & (hundred >= self._count_lanes)):
                    m.d.sync += [low.eq(stage[-1][1]), found_low.eq(1)]
                with m.If(~found_high & (hundred >= ninety_nine)):
                    m.d.sync += [high.eq(stage[-1][1]), found_high.eq(1)]
            with m.If(level == 265 + extra):
                m.d.sync += [scanning.eq(0), building.eq(1)]
        # the table: value v stretches to min((v - low) * 255 // span, 255), built from v = 0 up
        value, quotient, remainder = Signal(9), Signal(9), Signal(18)
        span = Signal(8)  # a register: the percentiles are found cycles before the table is built
        m.d.sync += span.eq(Mux(high > low, high - low, 1))
        m.d.comb += [self._table_address.eq(value[:8]), self._table_entry.eq(quotient[:8]),
                     self._table_write.eq(~((remainder >= span) & (quotient < 255)))]
        with m.If(building):
            with m.If((remainder >= span) & (quotient < 255)):
                m.d.sync += [remainder.eq(remainder - span), quotient.eq(quotient + 1)]
            with m.Elif(value == 255):
                m.d.sync += [building.eq(0), value.eq(0), quotient.eq(0), remainder.eq(0)]
            with m.Else():
                m.d.sync += value.eq(value + 1)
                with m.If(value >= low):
                    m.d.sync += remainder.eq(remainder + 255)
        return (settle != 0) | scanning | building

    def elaborate(self, platform: object) -> Module:
        if self.lanes == 1:
            self._low = Signal(8, init=0)
            self._high = Signal(8, init=255)
            self._histogram = Memory(shape=unsigned(32), depth=256, init=[])
            self._count = Signal(32)
        return super().elaborate(platform)

    def post(self, m: Module, value: Value) -> Value:
        span = Mux(self._high > self._low, self._high - self._low, 1)
        above = Mux(value > self._low, value - self._low, 0)
        stretched = (above * 255) // span
        return Mux(stretched > 255, 255, stretched)[:8]

    def observe(self, m: Module, value: Value, taken: Value) -> None:
        m.submodules.histogram = self._histogram
        self._read = self._histogram.read_port(domain="comb")
        self._write = self._histogram.write_port()
        self._scanning = Signal()
        with m.If(~self._scanning):
            m.d.comb += [self._read.addr.eq(value), self._write.addr.eq(value),
                         self._write.data.eq(self._read.data + 1), self._write.en.eq(taken)]
        with m.If(taken):
            m.d.sync += self._count.eq(self._count + 1)

    def between_frames(self, m: Module, ended: Value) -> Value:
        """Walk the histogram once: the percentiles for the next frame, each bin cleared behind."""
        level = Signal(9)
        running = Signal(32)
        found_low, found_high = Signal(), Signal()
        low, high = Signal(8), Signal(8)
        scanning = self._scanning
        with m.If(ended):
            m.d.sync += [scanning.eq(1), level.eq(0), running.eq(0), found_low.eq(0), found_high.eq(0)]
        with m.If(scanning):
            total = running + self._read.data
            reaches_low = (total * 100) >= self._count
            reaches_high = (total * 100) >= self._count * 99
            m.d.comb += [self._read.addr.eq(level), self._write.addr.eq(level), self._write.data.eq(0),
                         self._write.en.eq(1)]
            m.d.sync += [running.eq(total), level.eq(level + 1)]
            with m.If(~found_low & reaches_low):
                m.d.sync += [low.eq(level), found_low.eq(1)]
            with m.If(~found_high & reaches_high):
                m.d.sync += [high.eq(level), found_high.eq(1)]
            with m.If(level == 255):
                m.d.sync += [scanning.eq(0), self._count.eq(0),
                             self._low.eq(Mux(found_low | reaches_low, Mux(found_low, low, level), 0)),
                             self._high.eq(Mux(found_high | reaches_high, Mux(found_high, high, level), 255))]
        return scanning
