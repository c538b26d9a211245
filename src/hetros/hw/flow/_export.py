"""Board export: an fpga target as a Vivado project for a Zynq board, up to the vendor tool.

``hetros hw export`` writes, per fpga target, into one folder:

- the synthesizable Verilog of the target (``_build``: topic networks, hardware nodes, TCPROS
  framers) and the Verilog sources of its Verilog nodes;
- ``<top>_axi.v``: the top as a block-design module: ``aclk``/``aresetn`` as Zynq systems
  clock and reset (active low), each gateway port an AXI4-Stream interface Vivado infers by name;
- ``build.tcl``: ``vivado -mode batch -source build.tcl`` makes the project, the block design
  (the processing system, one AXI DMA per gateway port, its control on the PS's general purpose
  port, its memory side on a high performance port), the bitstream, and copies ``<top>.bit`` and
  ``<top>.hwh`` (what PYNQ's ``Overlay`` loads) next to the manifest;
- ``<top>.board.json``: the manifest the host side reads (``hetros.launch.system.board``): the board, each port
  with its width, and per gateway port its DMA (name, base address, ``sendchannel`` for software
  -> hardware, ``recvchannel`` back), topic and type; each memory node's AXI4 master, wired to the
  processing system's memory port.

The addresses are fixed by the Tcl (``assign_bd_address -offset``), so the manifest holds before
Vivado runs.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..._errors import HardwareError
from ...msg import TypeRegistry
from ...plan import Plan, gateway_node
from ..top._build import build, top_name


@dataclass(frozen=True)
class Board:
    name: str
    part: str
    processing_system: str  # the Vivado IP of its processing system
    control_port: str  # the PS's AXI master for the DMAs' registers
    memory_port: str  # the PS's AXI slave the DMAs reach memory through
    dma_base: int  # where the first DMA's registers go; one 64 KiB page each after it
    clock_pin: str  # the PS clock that drives the fabric
    board_part: str  # Vivado's board part: its preset configures the processing system's DDR, MIO and clocks


BOARDS = {
    "zcu104": Board("zcu104", "xczu7ev-ffvc1156-2-e", "zynq_ultra_ps_e", "M_AXI_HPM0_FPD", "S_AXI_HP0_FPD",
                    0xA000_0000, "pl_clk0", "xilinx.com:zcu104:part0:1.1"),
    "ultra96": Board("ultra96", "xczu3eg-sbva484-1-i", "zynq_ultra_ps_e", "M_AXI_HPM0_FPD", "S_AXI_HP0_FPD",
                     0xA000_0000, "pl_clk0", "avnet.com:ultra96v2:part0:1.2"),
    "pynq-z2": Board("pynq-z2", "xc7z020clg400-1", "processing_system7", "M_AXI_GP0", "S_AXI_HP0",
                     0x4040_0000, "FCLK_CLK0", "tul.com.tw:pynq-z2:part0:1.0"),
}
_DMA_PAGE = 0x1_0000


def board_of(name: str) -> Board:
    if name not in BOARDS:
        raise HardwareError(f"board must be one of {', '.join(sorted(BOARDS))}, not {name!r}")
    return BOARDS[name]


def export(plan: Plan, target: str, board_name: str, out: Path, types: TypeRegistry) -> list[Path]:
    """Write the Vivado project of ``target`` for ``board_name`` into ``out``; the files written."""
    board = board_of(board_name)
    verilog, core_manifest = build(plan, target, out, types)
    core = json.loads(core_manifest.read_text())
    top = top_name(target)
    streams = _stream_ports(core["ports"])
    gateway = gateway_node(target)
    dmas = []
    for index, (interface, port) in enumerate(sorted(streams.items())):
        sends = interface.startswith("s_axis_")  # software -> hardware: the DMA reads memory into it
        dmas.append({
            "name": f"axi_dma_{index}", "interface": interface, "base_address": hex(board.dma_base + index * _DMA_PAGE),
            "channel": "sendchannel" if sends else "recvchannel", "topic": port["topic"],
            "node": port["node"], "width": port["width"],
            "tcpros": port["node"] == "tcpros",
            "gateway": port["node"] == gateway,
        })
    wrapper = out / f"{top}_axi.v"
    wrapper.write_text(_wrapper(top, core["ports"], bool(core["ports"] and core["ports"][0]["name"] == "clk")))
    manifest = {
        "board": board.name, "part": board.part, "top": f"{top}_axi", "core": top, "target": target,
        "clock_mhz": core["clock_mhz"], "data_width": core["data_width"], "beats": core["beats"],
        "bitstream": f"{top}.bit", "hwh": f"{top}.hwh",
        "ports": [{"name": "aclk", "direction": "input", "width": 1, "role": "clock"},
                  {"name": "aresetn", "direction": "input", "width": 1, "role": "reset (active low)"}]
        + [p for p in core["ports"] if p.get("interface")],
        "dmas": dmas, "topics": core["topics"],
        # hardware nodes reading messages in memory: their AXI4 masters reach DDR through the PS's memory port
        "memory_masters": [dict(m, reaches=board.memory_port) for m in core.get("memory_masters", [])],
        "verilog_sources": [verilog.name, wrapper.name, *core["verilog_sources"]],
    }
    manifest_path = out / f"{top}.board.json"
    manifest_path.write_text(json.dumps(manifest, indent=1))
    tcl = out / "build.tcl"
    tcl.write_text(_tcl(board, manifest))
    return [verilog, wrapper, manifest_path, tcl, *(out / s for s in core["verilog_sources"])]


def _stream_ports(ports: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """The AXI4-Stream interfaces of the core by name, with their topic, node and data width."""
    interfaces: dict[str, dict[str, Any]] = {}
    for port in ports:
        if port.get("interface") and port.get("topic"):
            entry = interfaces.setdefault(port["interface"], {"topic": port["topic"], "node": port["node"]})
            if port["name"].endswith("_tdata"):
                entry["width"] = port["width"]
    return interfaces


def _wrapper(core: str, ports: list[dict[str, Any]], clocked: bool) -> str:
    """The block-design module around the core: Zynq's clock and active-low reset, every stream as it is."""
    streams = [p for p in ports if p.get("interface")]
    interfaces = sorted({p["interface"] for p in streams})
    lines = ["// Generated by hetros hw export: DO NOT EDIT.",
             f"// {core} as a block-design module: aclk, aresetn, and its AXI4-Stream ports.",
             "`default_nettype none", "",
             f"module {core}_axi ("]
    # the clock's interface and its association with every stream and the reset sit on the aclk port, where
    # Vivado's block design reads them (on the module they are ignored, and the streams get no clock)
    declarations = [
        "  (* X_INTERFACE_INFO = \"xilinx.com:signal:clock:1.0 aclk CLK\", X_INTERFACE_PARAMETER = "
        f"\"ASSOCIATED_BUSIF {':'.join(interfaces)}, ASSOCIATED_RESET aresetn\" *)\n  input wire aclk",
        "  (* X_INTERFACE_INFO = \"xilinx.com:signal:reset:1.0 aresetn RST\", X_INTERFACE_PARAMETER = "
        "\"POLARITY ACTIVE_LOW\" *)\n  input wire aresetn"]
    for port in streams:
        width = f"[{port['width'] - 1}:0] " if port["width"] > 1 else ""
        declarations.append(f"  {port['direction']} wire {width}{port['name']}")
    lines.append(",\n".join(declarations))
    lines += [");", ""]
    connections = ([".clk(aclk)", ".rst(~aresetn)"] if clocked else []) + [
        f".{p['name']}({p['name']})" for p in streams]
    lines.append(f"  {core} core (")
    lines.append(",\n".join(f"    {c}" for c in connections))
    lines += ["  );", "endmodule", "`default_nettype wire", ""]
    return "\n".join(lines)


def _tcl(board: Board, manifest: dict[str, Any]) -> str:
    """Vivado batch script: project, block design, bitstream, and the .bit/.hwh PYNQ loads."""
    top = manifest["top"]
    core = manifest["core"]
    mhz = manifest["clock_mhz"]
    zynqmp = board.processing_system == "zynq_ultra_ps_e"
    lines = [
        "# Generated by hetros hw export: DO NOT EDIT. Run: vivado -mode batch -source build.tcl",
        f"# board {board.name}, part {board.part}, fpga target {manifest['target']}, {mhz} MHz",
        "set here [file dirname [file normalize [info script]]]",
        f"create_project -force {core} $here/vivado -part {board.part}",
        f"set_property board_part {board.board_part} [current_project]",
        "add_files -norecurse [list " + " ".join(f"$here/{s}" for s in manifest["verilog_sources"]) + "]",
        "update_compile_order -fileset sources_1",
        "create_bd_design hetros",
        f"set ps [create_bd_cell -type ip -vlnv xilinx.com:ip:{board.processing_system} ps]",
    ]
    # the board's preset first (DDR, MIO, the PS's clocks as the board wires them), then what hetros needs
    if zynqmp:
        lines += ["apply_bd_automation -rule xilinx.com:bd_rule:zynq_ultra_ps_e -config {apply_board_preset \"1\"} $ps",
                  f"set_property -dict [list CONFIG.PSU__USE__M_AXI_GP0 {{1}} CONFIG.PSU__USE__S_AXI_GP2 {{1}} "
                  f"CONFIG.PSU__CRL_APB__PL0_REF_CTRL__FREQMHZ {{{mhz:g}}}] $ps"]
    else:
        lines += ["apply_bd_automation -rule xilinx.com:bd_rule:processing_system7 "
                  "-config {make_external \"FIXED_IO, DDR\" apply_board_preset \"1\"} $ps",
                  f"set_property -dict [list CONFIG.PCW_USE_S_AXI_HP0 {{1}} "
                  f"CONFIG.PCW_FPGA0_PERIPHERAL_FREQMHZ {{{mhz:g}}}] $ps"]
    lines += [
        f"set clock [get_bd_pins ps/{board.clock_pin}]",
        f"set hetros [create_bd_cell -type module -reference {top} hetros]",
        "connect_bd_net $clock [get_bd_pins hetros/aclk]",
        "set reset [create_bd_cell -type ip -vlnv xilinx.com:ip:proc_sys_reset reset]",
        "connect_bd_net $clock [get_bd_pins reset/slowest_sync_clk]",
        f"connect_bd_net [get_bd_pins ps/{'pl_resetn0' if zynqmp else 'FCLK_RESET0_N'}] "
        "[get_bd_pins reset/ext_reset_in]",
        "connect_bd_net [get_bd_pins reset/peripheral_aresetn] [get_bd_pins hetros/aresetn]",
    ]
    for dma in manifest["dmas"]:
        name, sends, width = dma["name"], dma["channel"] == "sendchannel", dma["width"]
        lines += [
            f"# {dma['name']}: {dma['topic']} ({'software -> hardware' if sends else 'hardware -> software'}), "
            f"{dma['interface']}",
            f"set dma [create_bd_cell -type ip -vlnv xilinx.com:ip:axi_dma {name}]",
            "set_property -dict [list CONFIG.c_include_sg {0} CONFIG.c_sg_length_width {26} "
            f"CONFIG.c_include_mm2s {{{int(sends)}}} CONFIG.c_include_s2mm {{{int(not sends)}}} "
            f"CONFIG.c_m_axis_mm2s_tdata_width {{{width}}} CONFIG.c_s_axis_s2mm_tdata_width {{{width}}} "
            # the memory-map side as wide as the stream (its default is 32 bits: a 64-bit stream would get
            # half the bandwidth, and a width converter, for nothing)
            f"CONFIG.c_m_axi_mm2s_data_width {{{width}}} CONFIG.c_m_axi_s2mm_data_width {{{width}}}"
            # a ZynqMP's DDR goes on above 4 GiB (from 0x8_0000_0000, on a board with more than 2 GiB): its DMAs
            # address 64 bits; the IP's default of 32 reaches the low 2 GiB only
            f"{' CONFIG.c_addr_width {64}' if zynqmp else ''}] $dma",
            (f"connect_bd_intf_net [get_bd_intf_pins {name}/M_AXIS_MM2S] [get_bd_intf_pins hetros/{dma['interface']}]"
             if sends else
             f"connect_bd_intf_net [get_bd_intf_pins hetros/{dma['interface']}] [get_bd_intf_pins {name}/S_AXIS_S2MM]"),
            "apply_bd_automation -rule xilinx.com:bd_rule:axi4 -config "
            f"[list Master {{/ps/{board.control_port}}} Clk {{Auto}}] [get_bd_intf_pins {name}/S_AXI_LITE]",
            "apply_bd_automation -rule xilinx.com:bd_rule:axi4 -config "
            f"[list Slave {{/ps/{board.memory_port}}} Clk {{Auto}}] "
            f"[get_bd_intf_pins {name}/{'M_AXI_MM2S' if sends else 'M_AXI_S2MM'}]",
            f"assign_bd_address -offset {dma['base_address']} -range 64K "
            f"[get_bd_addr_segs {name}/S_AXI_LITE/Reg]",
        ]
    for master in manifest["memory_masters"]:
        lines += [f"# {master['interface']}: node {master['node']} reads and writes messages in memory",
                  "apply_bd_automation -rule xilinx.com:bd_rule:axi4 -config "
                  f"[list Slave {{/ps/{board.memory_port}}} Clk {{Auto}}] "
                  f"[get_bd_intf_pins hetros/{master['interface']}]"]
    lines += [
        "validate_bd_design",
        "save_bd_design",
        "make_wrapper -files [get_files hetros.bd] -top -import",
        "launch_runs impl_1 -to_step write_bitstream -jobs 4",
        "wait_on_run impl_1",
        f"file copy -force [glob $here/vivado/{core}.runs/impl_1/*.bit] $here/{core}.bit",
        f"file copy -force [glob $here/vivado/{core}.gen/sources_1/bd/hetros/hw_handoff/hetros.hwh] $here/{core}.hwh",
        "",
    ]
    return "\n".join(lines)
