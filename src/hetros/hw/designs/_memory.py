"""Hardware nodes that read and write messages in memory (ReconROS's MEMIF), by address, over AXI4.

A node with ``memory: [/in, /out]`` gets, instead of each ``/in`` message as a stream, a
*descriptor* on its ``in`` port: for every array of numbers of the message (in field order) its
address and its length in bytes, then the same for the ``/out`` message the gateway has loaned
for the answer (its arrays as long as the input's, its other fields copied); each an
8-byte-aligned little-endian uint64. The node reads and writes those arrays through its AXI4
master port ``mem`` and, when the answer is written, sends one beat on its ``out`` port; the
gateway then publishes the loaned message. Images go from the camera's shared-memory slot to
the hardware and from the hardware to the display's with no CPU copy: in co-simulation the
memory model behind ``mem`` serves those slots at the physical addresses the gateway placed them
at (``_verilator.PhysicalSpace``), and accesses outside the descriptor's arrays stop the launch
with an error naming the node. On a ``board:`` target the arrays go through PYNQ's contiguous
buffers instead (``launch.system._gateway._BoardMemory``).
"""

from __future__ import annotations

from amaranth import Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..._errors import HardwareError
from ..streams._axi import axi_stream
from ..streams._ports import port_part
from ._image import Sobel

MEMORY_PORT = "mem"
ADDRESS_BITS = 64
# beats of one burst (AXI4 allows 256; 16 keeps a burst within what every interconnect buffers)
BURST = 16

AXI4_CHANNELS = {
    "aw": ("awaddr", "awlen", "awsize", "awburst", "awvalid"), "w": ("wdata", "wstrb", "wlast", "wvalid"),
    "ar": ("araddr", "arlen", "arsize", "arburst", "arvalid"),
}


def axi4_memory(data_width: int) -> wiring.Signature:
    """An AXI4 master (the node's side): 64-bit addresses, ``data_width`` data, INCR bursts, no IDs."""
    if data_width not in (32, 64, 128, 256, 512):
        raise HardwareError(f"an AXI4 memory port's data_width must be 32, 64, 128, 256 or 512 bits, "
                            f"not {data_width!r}")
    return wiring.Signature({
        "awaddr": Out(ADDRESS_BITS), "awlen": Out(8), "awsize": Out(3), "awburst": Out(2), "awvalid": Out(1),
        "awready": In(1),
        "wdata": Out(data_width), "wstrb": Out(data_width // 8), "wlast": Out(1), "wvalid": Out(1), "wready": In(1),
        "bresp": In(2), "bvalid": In(1), "bready": Out(1),
        "araddr": Out(ADDRESS_BITS), "arlen": Out(8), "arsize": Out(3), "arburst": Out(2), "arvalid": Out(1),
        "arready": In(1),
        "rdata": In(data_width), "rresp": In(2), "rlast": In(1), "rvalid": In(1), "rready": Out(1),
    })


def _burst_beats(m: Module, address: Signal, left: Signal, per_beat: int) -> tuple[Signal, Signal]:
    """Beats of the next burst from ``address`` with ``left`` beats to go: at most BURST, never across 4 KiB.

    The count is a register, a cycle behind ``address`` and ``left`` (so no 64-bit address adder feeds
    it in the cycle it is used); ``settled`` says it is of their present values: a caller that changes
    either clears it (``m.d.sync += settled.eq(0)``, after this call) and asks for no burst until it is
    set again."""
    to_boundary = Signal(range(4096 // per_beat + 1))
    m.d.comb += to_boundary.eq((4096 - address[:12]) >> (per_beat.bit_length() - 1))
    beats = Signal(range(BURST + 1))
    settled = Signal()
    m.d.sync += [beats.eq(Mux(left < BURST, Mux(left < to_boundary, left, to_boundary),
                              Mux(to_boundary < BURST, to_boundary, BURST))), settled.eq(1)]
    return beats, settled


class MemorySobel(wiring.Component):
    """The Sobel node reading its image and writing its edges in memory (``examples/sobel_hw/project_mem.yaml``).

    The descriptor is four words (``data``'s address and length, in and out). The pixels are read in
    bursts and go through the streaming :class:`Sobel` (behind a synthetic CDR header giving it the line
    length, ``width``); its output pixels are written back in bursts. Mono8, ``width`` pixels a line
    (the node's parameter, as the streaming one's line buffers), 64-bit data.
    """

    def __init__(self, source: str, sink: str, data_width: int = 64, width: int = 640) -> None:
        if data_width != 64:
            raise HardwareError(f"MemorySobel's data_width must be 64, not {data_width!r}")
        self._source, self._sink, self.width = port_part(source), port_part(sink), width
        super().__init__({self._source: In(axi_stream(64)), self._sink: Out(axi_stream(64)),
                          MEMORY_PORT: Out(axi4_memory(64))})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        descriptors, done, mem = getattr(self, self._source), getattr(self, self._sink), getattr(self, MEMORY_PORT)
        m.submodules.sobel = sobel = Sobel("/pixels_in", "/pixels_out", 64, self.width)
        pixels_in, pixels_out = sobel.pixels_in, sobel.pixels_out
        words = [Signal(64, name=n) for n in ("src", "src_len", "dst", "dst_len")]
        taken = Signal(range(5))
        busy = Signal()
        kick = Signal()
        m.d.comb += descriptors.tready.eq(~busy)
        with m.If(descriptors.tvalid & descriptors.tready):
            with m.Switch(taken):
                for index, word in enumerate(words):
                    with m.Case(index):
                        m.d.sync += word.eq(descriptors.tdata)
            m.d.sync += taken.eq(taken + 1)
            with m.If(descriptors.tlast):
                m.d.sync += [busy.eq(1), taken.eq(0), kick.eq(1)]
        with m.If(kick):  # the descriptor is in: read and write from the next cycle on
            m.d.sync += kick.eq(0)
        src, src_len, dst, dst_len = words
        total_beats = Signal(40)
        m.d.comb += total_beats.eq((src_len + 7) >> 3)
        tail = Signal(4)
        m.d.comb += tail.eq(Mux(src_len[:3] == 0, 8, src_len[:3]))

        # the synthetic CDR header: stamp, frame_id "", height, width, encoding "", is_bigendian, step, data's length
        header = [Const(0, 64), Const(1, 64), Const(0, 64), Const(1, 64), Cat(Const(self.width, 32), src_len[:32])]
        feeding = Signal(2)  # 0 idle, 1 header, 2 pixels
        header_beat = Signal(range(len(header)))
        read_left = Signal(40)  # beats not yet asked for
        read_address = Signal(64)
        reading = Signal()  # a burst asked for and not finished
        read_beats, read_settled = _burst_beats(m, read_address, read_left, 8)
        pixels_left = Signal(40)  # beats not yet delivered
        m.d.comb += [mem.arsize.eq(3), mem.arburst.eq(1), mem.awsize.eq(3), mem.awburst.eq(1)]
        with m.If(kick):
            m.d.sync += [feeding.eq(1), header_beat.eq(0), read_left.eq(total_beats), read_address.eq(src),
                         pixels_left.eq(total_beats), read_settled.eq(0)]
        with m.If(feeding == 1):
            with m.Switch(header_beat):
                for index, value in enumerate(header):
                    with m.Case(index):
                        m.d.comb += pixels_in.tdata.eq(value)
            m.d.comb += [pixels_in.tvalid.eq(1), pixels_in.tkeep.eq(0xFF), pixels_in.tlast.eq(total_beats == 0)]
            with m.If(pixels_in.tready):
                m.d.sync += header_beat.eq(header_beat + 1)
                with m.If(header_beat == len(header) - 1):
                    m.d.sync += feeding.eq(2)
        with m.If((feeding == 2) & ~reading & (read_left != 0) & read_settled):
            m.d.comb += [mem.arvalid.eq(1), mem.araddr.eq(read_address), mem.arlen.eq(read_beats - 1)]
            with m.If(mem.arready):
                m.d.sync += [reading.eq(1), read_left.eq(read_left - read_beats),
                             read_address.eq(read_address + (read_beats << 3)), read_settled.eq(0)]
        last_pixels = pixels_left == 1
        with m.If(feeding == 2):
            m.d.comb += [pixels_in.tdata.eq(mem.rdata), pixels_in.tvalid.eq(mem.rvalid),
                         mem.rready.eq(pixels_in.tready), pixels_in.tlast.eq(last_pixels),
                         pixels_in.tkeep.eq(Mux(last_pixels, (Const(1, 9) << tail) - 1, 0xFF))]
            with m.If(mem.rvalid & mem.rready):
                m.d.sync += pixels_left.eq(pixels_left - 1)
                with m.If(mem.rlast):
                    m.d.sync += reading.eq(0)
                with m.If(last_pixels):
                    m.d.sync += feeding.eq(0)

        # the filter's output: its 5 header beats dropped, the pixels written in bursts
        dropped = Signal(range(len(header) + 1))
        write_left = Signal(40)
        write_address = Signal(64)
        in_burst = Signal(range(BURST + 1))  # W beats left of the burst under way
        waiting_b = Signal()
        written_all = Signal()
        started = Signal()
        write_beats, write_settled = _burst_beats(m, write_address, write_left, 8)
        with m.If(kick):
            m.d.sync += [started.eq(1), dropped.eq(0), write_left.eq((dst_len + 7) >> 3), write_address.eq(dst),
                         written_all.eq(0), write_settled.eq(0)]
        with m.If(started & (dropped < len(header))):
            m.d.comb += pixels_out.tready.eq(1)
            with m.If(pixels_out.tvalid):
                m.d.sync += dropped.eq(dropped + 1)
        with m.Elif(started & ~written_all):
            with m.If((in_burst == 0) & ~waiting_b & (write_left != 0) & write_settled):
                m.d.comb += [mem.awvalid.eq(1), mem.awaddr.eq(write_address), mem.awlen.eq(write_beats - 1)]
                with m.If(mem.awready):
                    m.d.sync += [in_burst.eq(write_beats), write_left.eq(write_left - write_beats),
                                 write_address.eq(write_address + (write_beats << 3)), write_settled.eq(0)]
            with m.If(in_burst != 0):
                m.d.comb += [mem.wvalid.eq(pixels_out.tvalid), mem.wdata.eq(pixels_out.tdata),
                             mem.wstrb.eq(pixels_out.tkeep), mem.wlast.eq(in_burst == 1),
                             pixels_out.tready.eq(mem.wready)]
                with m.If(mem.wvalid & mem.wready):
                    m.d.sync += in_burst.eq(in_burst - 1)
                    with m.If(in_burst == 1):
                        m.d.sync += waiting_b.eq(1)
            with m.If(waiting_b):
                m.d.comb += mem.bready.eq(1)
                with m.If(mem.bvalid):
                    m.d.sync += waiting_b.eq(0)
                    with m.If(write_left == 0):
                        m.d.sync += written_all.eq(1)
        with m.If(written_all):
            m.d.comb += [done.tvalid.eq(1), done.tdata.eq(1), done.tkeep.eq(0xFF), done.tlast.eq(1)]
            with m.If(done.tready):
                m.d.sync += [written_all.eq(0), started.eq(0), busy.eq(0)]
        return m
