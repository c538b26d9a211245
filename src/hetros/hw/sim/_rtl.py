"""The exported Verilog of a topic network under Icarus Verilog, driven as the Amaranth testbench drives it.

The testbench is generated: every publisher's beats come from a ``$readmemh`` file, and the
per-cycle idle and stall decisions of an Amaranth run (``SimResult.idle``/``stall``) are
replayed bit for bit, so both simulators must agree on every beat and every cycle. Icarus is
also much faster than Amaranth's Python simulator, which makes it the one the reports use
for megabyte messages.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from amaranth.back import verilog

from ..._errors import HardwareError
from ..streams._beats import Beats, from_beats, to_beats
from ..top._build import FpgaTop, HardwareTopic
from ._sim import SimResult

TOP = "hetros_topic"


def icarus_available() -> bool:
    return shutil.which("iverilog") is not None and shutil.which("vvp") is not None


def topic_verilog(publishers: int, subscribers: int, data_width: int, fifo_depth: int | None) -> tuple[str, FpgaTop]:
    """One topic network as a Verilog top with AXI-Stream ports ``s_axis_t_p<i>_*`` and ``m_axis_t_s<j>_*``."""
    topic = HardwareTopic("/t", "", tuple(f"p{i}" for i in range(publishers)),
                          tuple(f"s{j}" for j in range(subscribers)), fifo_depth)
    top = FpgaTop([topic], data_width)
    return verilog.convert(top, name=TOP, ports=top.signals()), top


def simulate_verilog(publishers: int, subscribers: int, data_width: int, fifo_depth: int | None,
                     messages: list[list[bytes]], *, idle: list[int] | None = None, stall: list[int] | None = None,
                     max_cycles: int = 50_000_000, workdir: Path | None = None) -> SimResult:
    """Run the exported network under Icarus; ``idle``/``stall`` replay an Amaranth run's decisions."""
    if not icarus_available():
        raise HardwareError("Icarus Verilog (iverilog, vvp) is not installed: `apt-get install iverilog` "
                            "(`make test` installs it when run as root)")
    if len(messages) != publishers:
        raise HardwareError(f"messages must list one sequence per publisher ({publishers}), not {len(messages)}")
    text, _top = topic_verilog(publishers, subscribers, data_width, fifo_depth)
    with tempfile.TemporaryDirectory(prefix="hetros-rtl-", dir=workdir) as folder:
        root = Path(folder)
        (root / f"{TOP}.v").write_text(text)
        counts = []
        for index, sent in enumerate(messages):
            counts.append(_write_beats(root / f"beats_p{index}.hex", sent, data_width))
        replay = idle is not None and stall is not None
        if replay:
            assert idle is not None and stall is not None
            (root / "idle.hex").write_text("".join(f"{bits:x}\n" for bits in idle) or "0\n")
            (root / "stall.hex").write_text("".join(f"{bits:x}\n" for bits in stall) or "0\n")
        expected = sum(len(sent) for sent in messages)
        cycles_in_table = len(idle) if idle is not None else 0
        clocked = "input clk;" in text  # a network of wiring only has no clock or reset port
        (root / "tb.v").write_text(_testbench(publishers, subscribers, data_width, counts, expected, replay,
                                              cycles_in_table, max_cycles, clocked))
        compiled = subprocess.run(["iverilog", "-g2012", "-o", "sim.vvp", "tb.v", f"{TOP}.v"], cwd=root,
                                  capture_output=True, text=True, check=False)
        if compiled.returncode:
            raise HardwareError(f"iverilog could not compile the testbench: {compiled.stderr.strip()}")
        ran = subprocess.run(["vvp", "-n", "sim.vvp"], cwd=root, capture_output=True, text=True, check=False)
        if ran.returncode or not (root / "out.txt").exists():
            raise HardwareError(f"vvp failed: {ran.stdout[-2000:]}{ran.stderr[-2000:]}")
        return _read_output(root / "out.txt", subscribers, data_width)


def _write_beats(path: Path, sent: list[bytes], data_width: int) -> int:
    """``{tlast, tkeep, tdata}`` per beat as hex lines; returns how many beats."""
    per_beat = data_width // 8
    lines: list[str] = []
    for message in sent:
        beats = to_beats(message, data_width)
        words = beats.words()
        for index, (word, keep) in enumerate(zip(words, beats.keep.tolist(), strict=True)):
            last = int(index == len(words) - 1)
            packed = (last << (data_width + per_beat)) | (int(keep) << data_width) | word
            lines.append(f"{packed:x}\n")
    path.write_text("".join(lines) or "0\n")
    return len(lines)


def _testbench(publishers: int, subscribers: int, width: int, counts: list[int], expected: int, replay: bool,
               table: int, max_cycles: int, clocked: bool) -> str:
    keep = width // 8
    packed = width + keep + 1
    lines = ["`timescale 1ns/1ps", "module tb;", "  reg clk = 0;", "  reg rst = 0;", "  integer cycle, out;"]
    ports = [".clk(clk)", ".rst(rst)"] if clocked else []
    for i in range(publishers):
        name = f"s_axis_t_p{i}"
        lines += [f"  reg [{width - 1}:0] {name}_tdata = 0;", f"  reg [{keep - 1}:0] {name}_tkeep = 0;",
                  f"  reg {name}_tlast = 0;", f"  reg {name}_tvalid = 0;", f"  wire {name}_tready;",
                  f"  reg [{packed - 1}:0] beats_p{i} [0:{max(counts[i], 1) - 1}];",
                  f"  integer ptr_p{i} = 0;", f"  reg showing_p{i} = 0;"]
        ports += [f".{name}_{f}({name}_{f})" for f in ("tdata", "tkeep", "tlast", "tvalid", "tready")]
    for j in range(subscribers):
        name = f"m_axis_t_s{j}"
        lines += [f"  wire [{width - 1}:0] {name}_tdata;", f"  wire [{keep - 1}:0] {name}_tkeep;",
                  f"  wire {name}_tlast;", f"  wire {name}_tvalid;", f"  reg {name}_tready = 0;",
                  f"  integer got_s{j} = 0;"]
        ports += [f".{name}_{f}({name}_{f})" for f in ("tdata", "tkeep", "tlast", "tvalid", "tready")]
    if replay:
        lines += [f"  reg [{publishers - 1}:0] idle_t [0:{max(table, 1) - 1}];",
                  f"  reg [{subscribers - 1}:0] stall_t [0:{max(table, 1) - 1}];"]
    lines.append(f"  {TOP} dut({', '.join(ports)});")
    done = " && ".join(f"got_s{j} >= {expected}" for j in range(subscribers))
    body = ["  initial begin", '    out = $fopen("out.txt", "w");']
    body += [f'    $readmemh("beats_p{i}.hex", beats_p{i});' for i in range(publishers)]
    if replay:
        body += ['    $readmemh("idle.hex", idle_t);', '    $readmemh("stall.hex", stall_t);']
    body.append(f"    for (cycle = 0; !({done}) && cycle < {max_cycles}; cycle = cycle + 1) begin")
    for i in range(publishers):
        name = f"s_axis_t_p{i}"
        starts = f"!idle_t[cycle][{i}]" if replay else "1"
        body += [f"      if (!showing_p{i} && ptr_p{i} < {counts[i]} && {starts}) showing_p{i} = 1;",
                 f"      if (showing_p{i}) {{{name}_tlast, {name}_tkeep, {name}_tdata}} = beats_p{i}[ptr_p{i}];",
                 f"      {name}_tvalid = showing_p{i};"]
    for j in range(subscribers):
        body.append(f"      m_axis_t_s{j}_tready = {f'!stall_t[cycle][{j}]' if replay else '1'};")
    body.append("      #1;")
    for i in range(publishers):
        body.append(f"      if (showing_p{i} && s_axis_t_p{i}_tready) begin ptr_p{i} = ptr_p{i} + 1; "
                    f"showing_p{i} = 0; end")
    for j in range(subscribers):
        name = f"m_axis_t_s{j}"
        body += [f"      if ({name}_tready && {name}_tvalid) begin",
                 f'        $fwrite(out, "{j} %0d %h %h %0d\\n", cycle, {name}_tdata, {name}_tkeep, {name}_tlast);',
                 f"        if ({name}_tlast) got_s{j} = got_s{j} + 1;",
                 "      end"]
    body += ["      clk = 1; #1; clk = 0; #1;", "    end", '    $fwrite(out, "cycles %0d\\n", cycle);',
             "    $fclose(out);", "    $finish;", "  end", "endmodule", ""]
    return "\n".join(lines + body)


def _read_output(path: Path, subscribers: int, data_width: int) -> SimResult:
    per_beat = data_width // 8
    received: list[list[bytes]] = [[] for _ in range(subscribers)]
    done_at: list[list[int]] = [[] for _ in range(subscribers)]
    partial: list[list[tuple[int, int]]] = [[] for _ in range(subscribers)]
    cycles = -1
    with path.open() as lines:
        for line in lines:
            fields = line.split()
            if fields[0] == "cycles":
                cycles = int(fields[1])
                continue
            sub, cycle, data, keep, last = int(fields[0]), int(fields[1]), int(fields[2], 16), int(fields[3], 16), \
                int(fields[4])
            partial[sub].append((data, keep))
            if last:
                words, keeps = zip(*partial[sub], strict=True)
                raw = np.frombuffer(b"".join(w.to_bytes(per_beat, "little") for w in words), np.uint8)
                received[sub].append(from_beats(Beats(raw.reshape(len(words), per_beat).copy(),
                                                      np.array(keeps, np.uint64))))
                done_at[sub].append(cycle)
                partial[sub].clear()
    if cycles < 0:
        raise HardwareError(f"the Icarus run ended without reporting its cycles ({path})")
    return SimResult(cycles, received, done_at)
