"""A hardware node written in Verilog (by hand, or by Vitis HLS), wrapped as an Amaranth component.

``hw: rtl/filter.v:filter_top`` names a file (relative to the project file) and a module in
it. The module's AXI4-Stream ports follow the same naming as Amaranth nodes: for a topic
``/image_raw``, ``image_raw_tdata``, ``_tkeep``, ``_tlast``, ``_tvalid`` and ``_tready``
(any case, so HLS's ``image_raw_TDATA`` serves too); ``tdata`` an input means the node
subscribes. The clock is ``clk``, ``ap_clk`` or ``aclk``; the reset ``rst`` (active high),
or ``ap_rst_n``/``aresetn``/``rst_n`` (active low). Node parameters whose names the module
declares as ``parameter`` are passed to it, as Amaranth nodes get theirs.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from amaranth import ClockSignal, Instance, Module, ResetSignal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .._errors import HardwareError
from ._stream import axi_stream

_FIELDS = ("tdata", "tkeep", "tlast", "tvalid", "tready")
_CLOCKS = ("clk", "ap_clk", "aclk")
_RESETS_HIGH = ("rst", "reset")
_RESETS_LOW = ("ap_rst_n", "aresetn", "rst_n")
_DECLARATION = re.compile(r"\b(input|output)\b\s*(?:wire|reg|logic)?\s*(?:signed)?\s*"
                          r"(\[\s*([^:\]]+?)\s*:\s*([^\]]+?)\s*\])?\s*([A-Za-z_][A-Za-z0-9_$]*(?:\s*,\s*(?!input|output)[A-Za-z_][A-Za-z0-9_$]*)*)")


@dataclass(frozen=True)
class VerilogPort:
    name: str
    direction: str
    width: int | None  # None: a range hetros does not evaluate (``[W-1:0]``)


@dataclass(frozen=True)
class VerilogModule:
    """What hetros reads of a module: its ports and parameters."""

    path: Path
    name: str
    ports: dict[str, VerilogPort]
    parameters: tuple[str, ...]


def is_verilog(hw: str) -> bool:
    return hw.partition(":")[0].endswith((".v", ".sv"))


def read_module(path: Path, name: str) -> VerilogModule:
    """The ports and parameters of module ``name`` in ``path`` (ANSI or classic port declarations)."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise HardwareError(f"hw: {path}:{name}: cannot read {path} ({exc.strerror})") from exc
    text = re.sub(r"//[^\n]*|/\*.*?\*/", " ", text, flags=re.S)
    found = re.search(rf"\bmodule\s+{re.escape(name)}\b(.*?)\bendmodule\b", text, flags=re.S)
    if found is None:
        modules = re.findall(r"\bmodule\s+([A-Za-z_][A-Za-z0-9_$]*)", text)
        raise HardwareError(f"hw: {path}:{name}: no module {name!r} in {path.name} (it has "
                            f"{', '.join(modules) or 'none'})")
    body = found.group(1)
    ports: dict[str, VerilogPort] = {}
    for direction, _range, high, low, names in _DECLARATION.findall(body):
        width = (abs(int(high) - int(low)) + 1 if high.isdigit() and low.isdigit() else None) if high else 1
        for port in (n.strip() for n in names.split(",")):
            if port:
                ports[port] = VerilogPort(port, direction, width)
    parameters = tuple(re.findall(r"\bparameter\b\s*(?:integer|int)?\s*(?:\[[^\]]*\])?\s*([A-Za-z_]\w*)", body))
    return VerilogModule(path, name, ports, parameters)


class VerilogNode(wiring.Component):
    """A Verilog module as a hardware node: one ``In``/``Out(axi_stream(data_width))`` member per stream
    port it has, found from its ``<port>_tdata`` ports (see the module's docstring)."""

    def __init__(self, module: VerilogModule, data_width: int, parameters: dict[str, Any]) -> None:
        self.module = module
        self.data_width = data_width
        self.parameters = {k: v for k, v in parameters.items() if k in module.parameters}
        lowered = {name.lower(): port for name, port in module.ports.items()}
        self._streams: dict[str, dict[str, VerilogPort]] = {}
        members = {}
        for name, port in lowered.items():
            if not name.endswith("_tdata"):
                continue
            stream = name.removesuffix("_tdata")
            fields = {field: lowered.get(f"{stream}_{field}") for field in _FIELDS}
            missing = [f"{stream}_{field}" for field, found in fields.items() if found is None]
            if missing:
                raise HardwareError(f"hw: {module.path}:{module.name}: stream {stream!r} lacks "
                                    f"{', '.join(missing)} (an AXI4-Stream port is tdata, tkeep, tlast, tvalid "
                                    "and tready)")
            self._streams[stream] = {f: p for f, p in fields.items() if p is not None}
            for field, bits in (("tdata", data_width), ("tkeep", data_width // 8)):
                if self._streams[stream][field].width not in (bits, None):
                    raise HardwareError(f"hw: {module.path}:{module.name}: {stream}_{field} must be {bits} bits "
                                        f"for the target's data_width {data_width}, not "
                                        f"{self._streams[stream][field].width}")
            members[stream] = In(axi_stream(data_width)) if port.direction == "input" else \
                Out(axi_stream(data_width))
        self.clock = next((lowered[c].name for c in _CLOCKS if c in lowered), None)
        reset = next(((lowered[r].name, True) for r in _RESETS_HIGH if r in lowered), None) or \
            next(((lowered[r].name, False) for r in _RESETS_LOW if r in lowered), None)
        self.reset = reset
        super().__init__(members)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        arguments: dict[str, Any] = {f"p_{k}": v for k, v in self.parameters.items()}
        if self.clock is not None:
            arguments[f"i_{self.clock}"] = ClockSignal()
        if self.reset is not None:
            name, high = self.reset
            arguments[f"i_{name}"] = ResetSignal() if high else ~ResetSignal()
        for stream, fields in self._streams.items():
            ours = getattr(self, stream)
            subscribes = fields["tdata"].direction == "input"
            for field, port in fields.items():
                towards_module = (field == "tready") != subscribes
                arguments[("i_" if towards_module else "o_") + port.name] = getattr(ours, field)
        m.submodules.verilog = Instance(self.module.name, **arguments)
        return m


def make_verilog_node(hw: str, root: str, data_width: int, parameters: dict[str, Any]) -> VerilogNode:
    """``path.v:module`` (relative to the project folder ``root``) as a hardware node."""
    file, _, name = hw.partition(":")
    path = Path(file) if Path(file).is_absolute() else Path(root) / file
    return VerilogNode(read_module(path, name), data_width, parameters)


def verilog_sources(components: dict[str, Any]) -> list[Path]:
    """The Verilog files the hardware nodes among ``components`` come from (a simulator reads them)."""
    return sorted({c.module.path.resolve() for c in components.values() if isinstance(c, VerilogNode)})
