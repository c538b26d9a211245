"""``hetros hw export``: a board's Vivado project, checked as far as the open tools reach.

Vivado is not here, so: every file is present, the block-design Tcl wires every AXI4-Stream
interface of the manifest to a DMA at the manifest's address, and the Verilog parses in Icarus and
passes Verilator's lint (but for two warnings Amaranth's Verilog carries by design: WIDTH, as
Amaranth truncates explicitly, and CASEINCOMPLETE, as its cases follow a default assignment).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("amaranth")
pytestmark = [pytest.mark.rtl,
              pytest.mark.skipif(shutil.which("verilator") is None or shutil.which("iverilog") is None,
                                 reason="Debian's verilator and iverilog are not installed")]

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize(("project", "board", "dma_base"), [
    ("sobel_hw/project_fpga.yaml", "zcu104", 0xA000_0000),
    ("hw_tcpros/project.yaml", "pynq-z2", 0x4040_0000),
    ("sobel_hw/project_mem.yaml", "ultra96", 0xA000_0000),
])
def test_export_writes_a_vivado_project_the_open_tools_accept(project: str, board: str, dma_base: int,
                                                              tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "hetros", "hw", "export", str(EXAMPLES / project), "--board", board,
                           "-o", str(tmp_path)], capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    manifest = json.loads((tmp_path / "hetros_fpga.board.json").read_text())
    assert manifest["board"] == board and manifest["top"] == "hetros_fpga_axi"
    for source in manifest["verilog_sources"]:
        assert (tmp_path / source).is_file(), source
    tcl = (tmp_path / "build.tcl").read_text()
    wrapper = (tmp_path / "hetros_fpga_axi.v").read_text()
    interfaces = {p["interface"] for p in manifest["ports"] if p.get("interface")}
    masters = {m["interface"] for m in manifest["memory_masters"]}
    assert interfaces == {d["interface"] for d in manifest["dmas"]} | masters
    for master in masters:  # a memory node's AXI4 master reaches DDR through the processing system
        assert f"[get_bd_intf_pins hetros/{master}]" in tcl and "S_AXI_HP0_FPD" in tcl
    assert ("mem" in project) == bool(masters)
    for port in manifest["ports"]:
        assert re.search(rf"\b{port['name']}\b", wrapper), port["name"]
    for dma in manifest["dmas"]:
        assert f"hetros/{dma['interface']}]" in tcl, dma
        assert f"assign_bd_address -offset {dma['base_address']} " in tcl
        assert ("M_AXIS_MM2S" if dma["channel"] == "sendchannel" else "S_AXIS_S2MM") in tcl
    for dma in manifest["dmas"]:  # the DMA's memory side as wide as its stream (its default is 32 bits)
        width = dma["width"]
        assert f"CONFIG.c_m_axi_mm2s_data_width {{{width}}} CONFIG.c_m_axi_s2mm_data_width {{{width}}}" in tcl
    # a ZynqMP's DMAs address its 64-bit physical space; a Zynq-7000's 32 bits (the IP's default) are all it has
    assert tcl.count("CONFIG.c_addr_width {64}") == (len(manifest["dmas"]) if board != "pynq-z2" else 0)
    # the board's preset before hetros's own settings, and the clock association on the aclk port itself
    part = {"zcu104": "xilinx.com:zcu104:part0:1.1", "pynq-z2": "tul.com.tw:pynq-z2:part0:1.0",
            "ultra96": "avnet.com:ultra96v2:part0:1.2"}[board]
    assert f"set_property board_part {part} [current_project]" in tcl
    preset = tcl.index('apply_board_preset "1"')
    assert preset < tcl.index("CONFIG.PSU__USE__M_AXI_GP0" if board != "pynq-z2" else "CONFIG.PCW_USE_S_AXI_HP0")
    assert re.search(r'\(\* X_INTERFACE_INFO = "xilinx.com:signal:clock:1.0 aclk CLK", X_INTERFACE_PARAMETER = '
                     r'"ASSOCIATED_BUSIF [\w:]+, ASSOCIATED_RESET aresetn" \*\)\n  input wire aclk', wrapper), wrapper
    assert not re.search(r"\*\)\s*module", wrapper), "the association belongs on the aclk port, not the module"
    addresses = sorted(int(d["base_address"], 16) for d in manifest["dmas"])
    assert addresses == [dma_base + 0x10000 * k for k in range(len(addresses))]
    assert "write_bitstream" in tcl and manifest["hwh"] in tcl and manifest["bitstream"] in tcl
    if "tcpros" in project:  # the ROS 1 side of the target: TCPROS frames on their own DMAs
        framed = {d["topic"]: d["channel"] for d in manifest["dmas"] if d["tcpros"]}
        assert framed == {"/chatter": "recvchannel", "/points": "recvchannel", "/ros1_chatter": "sendchannel"}
    sources = [str(tmp_path / s) for s in manifest["verilog_sources"]]
    parsed = subprocess.run(["iverilog", "-g2012", "-o", str(tmp_path / "parsed"), "-s", "hetros_fpga_axi", *sources],
                            capture_output=True, text=True, check=False)
    assert parsed.returncode == 0, parsed.stderr
    lint = subprocess.run(["verilator", "--lint-only", "-Wno-WIDTH", "-Wno-CASEINCOMPLETE", "--top-module",
                           "hetros_fpga_axi", *sources], capture_output=True, text=True, check=False)
    assert lint.returncode == 0, lint.stderr


def test_the_open_flow_makes_an_ecp5_bitstream_and_reports_fmax(tmp_path: Path) -> None:
    from hetros.hw.flow._bitstream import available

    if not available():
        pytest.skip("YoWASP's nextpnr-ecp5 and ecppack are not installed (pip install 'hetros[rtl]')")
    project = EXAMPLES / "hw_topics" / "project.yaml"
    done = subprocess.run([sys.executable, "-m", "hetros", "hw", "bitstream", str(project), "--parts", "parts", "-o",
                           str(tmp_path)], capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr
    rows = re.findall(r"^\| (topic \S+ \(\d->\d\)) \| (LFE5U-\S+) \| [\d,]+ \| [\d,]+ \| ([\d.]+) MHz \| 100 MHz \| "
                      r"(\S+\.bit)", done.stdout, re.MULTILINE)
    assert {r[0] for r in rows} == {"topic /image (1->2)", "topic /features (2->2)"}, done.stdout
    for _design, _device, fmax, name in rows:
        assert float(fmax) > 10
        bitstream = next(tmp_path.rglob(name)).read_bytes()
        assert b"\xff\xff\xbd\xb3" in bitstream[:4096], "no ECP5 preamble: not a bitstream"


def _fresh_hetros_cache(folder: Path) -> Path:
    """A cache folder without hetros's cached Fmax figures, sharing the tools' compiled WebAssembly (YoWASP,
    wasmtime: half a minute to build) with the user's cache."""
    shared = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    folder.mkdir(parents=True)
    for tool in ("YoWASP", "wasmtime"):
        (shared / tool).mkdir(parents=True, exist_ok=True)
        (folder / tool).symlink_to(shared / tool)
    return folder


def test_a_design_that_misses_its_clock_fails_the_bitstream_and_slows_its_figures(tmp_path: Path) -> None:
    """Timing is a check: at 400 MHz the topic networks of examples/hw_topics miss their clock on an ECP5;
    `hw bitstream` exits 1 naming the critical path, and the target's figures then use the Fmax achieved."""
    from hetros.hw.flow._bitstream import available

    if not available():
        pytest.skip("YoWASP's nextpnr-ecp5 and ecppack are not installed (pip install 'hetros[rtl]')")
    example = EXAMPLES / "hw_topics"
    shutil.copytree(example, tmp_path / "hw_topics")
    project = tmp_path / "hw_topics" / "project.yaml"
    project.write_text(project.read_text().replace("clock_mhz: 100", "clock_mhz: 400"))
    env = dict(os.environ, XDG_CACHE_HOME=str(_fresh_hetros_cache(tmp_path / "cache")))
    done = subprocess.run([sys.executable, "-m", "hetros", "hw", "bitstream", str(project), "--parts", "target", "-o",
                           str(tmp_path / "out")], capture_output=True, text=True, timeout=600, check=False, env=env)
    assert done.returncode == 1, done.stdout + done.stderr
    achieved = re.search(r"^\| fpga0 \| \S+ \| [\d,]+ \| [\d,]+ \| ([\d.]+) MHz \(misses the clock\) \| 400 MHz \|",
                         done.stdout, re.MULTILINE)
    assert achieved is not None, done.stdout
    assert re.search(r"error: fpga0 misses its clock: place and route achieved [\d.]+ MHz on LFE5U-\S+, clock_mhz is "
                     r"400 MHz; its critical path, in \S+: \S+ -> \S+: [\d.]+ ns over \d+ logic levels", done.stderr), \
        done.stderr
    clock = subprocess.run([sys.executable, "-c", textwrap.dedent(f"""
        from hetros.hw import target_clock
        from hetros.project import load_project, plan
        clock = target_clock(plan(load_project({str(project)!r})), "fpga0")
        print(clock.mhz, clock.source)
    """)], capture_output=True, text=True, timeout=300, check=False, env=env)
    assert clock.returncode == 0, clock.stderr
    mhz, _, source = clock.stdout.strip().partition(" ")
    assert abs(float(mhz) - float(achieved.group(1))) < 0.1
    assert source.startswith("the Fmax place and route achieved on LFE5U")
