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

from collections.abc import Callable
from typing import Any

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.hdl import Value
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .._errors import HardwareError
from ._build import port_part
from ._bytes import bytes_in, bytes_out
from ._stream import axi_stream

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

    def __init__(self, source: str, sink: str, data_width: int = 64, width: int = 640, channels: int = 1) -> None:
        if width < 3:
            raise HardwareError(f"width must be at least 3 pixels, not {width!r}")
        if channels < 1:
            raise HardwareError(f"channels must be at least 1, not {channels!r}")
        self._source, self._sink = port_part(source), port_part(sink)
        self.data_width, self.width, self.channels = data_width, width, channels
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


def _widened(value: Value) -> Value:
    """An unsigned sum as a signed value of one more bit, so differences keep their sign."""
    return Cat(value, Const(0, 1)).as_signed()


class Sobel(ImageFilter3x3):
    """Edges: ``min(|Gx| + |Gy|, 255)`` with the 3x3 Sobel kernels (``hetros.hw.reference.sobel`` in software)."""

    def reference(self) -> Callable[[np.ndarray[Any, Any]], np.ndarray[Any, Any]] | None:
        from .reference import sobel

        return sobel

    def kernel(self, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        right, left = [top[2], middle[2], bottom[2]], [top[0], middle[0], bottom[0]]
        gx = _widened(_row_sum(right)) - _widened(_row_sum(left))
        gy = _widened(_row_sum(bottom)) - _widened(_row_sum(top))
        magnitude = Mux(gx < 0, -gx, gx) + Mux(gy < 0, -gy, gy)
        return Mux(magnitude > 255, 255, magnitude)[:8]


class GaussianBlur(ImageFilter3x3):
    """3x3 Gaussian ``[1 2 1; 2 4 2; 1 2 1] / 16``, rounded half up (in software:
    ``hetros.hw.reference.gaussian_blur``)."""

    def reference(self) -> Callable[[np.ndarray[Any, Any]], np.ndarray[Any, Any]] | None:
        from .reference import gaussian_blur

        return gaussian_blur

    def kernel(self, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        total = _row_sum(top) + (_row_sum(middle) << 1) + _row_sum(bottom) + 8
        return (total >> 4)[:8]


# Paeth's 19 compare-exchanges that leave the median of nine in position 4
_MEDIAN9 = ((1, 2), (4, 5), (7, 8), (0, 1), (3, 4), (6, 7), (1, 2), (4, 5), (7, 8), (0, 3), (5, 8), (4, 7),
            (3, 6), (1, 4), (2, 5), (4, 7), (4, 2), (6, 4), (4, 2))


class Compensation(ImageFilter3x3):
    """The lane-following vehicle's image compensation: outliers out with a 3x3 median of each channel,
    then a contrast stretch between the 1st and 99th percentile of the previous frame's median image
    (its histogram is counted as the frame streams by and read between frames, so no frame buffer is
    needed; the first frame is not stretched). ``hetros.hw.reference.Compensation`` in software."""

    def reference(self) -> Callable[[np.ndarray[Any, Any]], np.ndarray[Any, Any]] | None:
        from .reference import Compensation as Twin

        return Twin()

    def kernel(self, top: list[Value], middle: list[Value], bottom: list[Value]) -> Value:
        values = [*top, *middle, *bottom]
        for a, b in _MEDIAN9:
            values[a], values[b] = Mux(values[a] < values[b], values[a], values[b]), \
                Mux(values[a] < values[b], values[b], values[a])
        return values[4]

    def elaborate(self, platform: object) -> Module:
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
