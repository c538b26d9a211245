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

import ast
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from amaranth import ClockSignal, Instance, Module, ResetSignal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..._errors import HardwareError
from ..streams._axi import axi_stream

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
    width: int | None  # None: a range of expressions (``[W-1:0]``), evaluated with the node's parameters
    high: str = ""
    low: str = ""

    def width_with(self, values: dict[str, int]) -> int:
        """The port's width once the module's parameters have ``values`` (HardwareError where the range
        is not a constant expression hetros can evaluate)."""
        if self.width is not None:
            return self.width
        return abs(constant(self.high, values) - constant(self.low, values)) + 1


@dataclass(frozen=True)
class VerilogModule:
    """What hetros reads of a module: its ports, parameters and the parameters' default expressions."""

    path: Path
    name: str
    ports: dict[str, VerilogPort]
    parameters: tuple[str, ...]
    defaults: tuple[tuple[str, str], ...] = ()

    def parameter_values(self, given: dict[str, Any]) -> dict[str, int]:
        """Each parameter's value: the node's where it gives one (an integer), else its default, evaluated
        in order (a default may use the parameters before it); those that are no integer are left out."""
        values: dict[str, int] = {}
        for name, default in self.defaults:
            value = given.get(name)
            if isinstance(value, int) and not isinstance(value, bool):
                values[name] = value
                continue
            try:
                values[name] = constant(default, values)
            except HardwareError:
                pass
        return values


_SIZED = re.compile(r"\d*\s*'\s*[sS]?\s*([dDhHbBoO])\s*([0-9a-fA-F_xXzZ]+)")
_BASES = {"d": 10, "h": 16, "b": 2, "o": 8}
_OPERATORS: dict[type[ast.operator], Callable[[int, int], int]] = {
    ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
    ast.FloorDiv: lambda a, b: a // b, ast.Mod: lambda a, b: a % b, ast.LShift: lambda a, b: a << b,
    ast.RShift: lambda a, b: a >> b, ast.Pow: lambda a, b: a**b,
}


def constant(text: str, values: dict[str, int]) -> int:
    """A Verilog constant expression of integers, parameters, + - * / % << >> ** and $clog2, as the
    module's elaboration would compute it (``/`` is integer division)."""
    def literal(found: re.Match[str]) -> str:
        return str(int(found.group(2).replace("_", ""), _BASES[found.group(1).lower()]))

    source = _SIZED.sub(literal, text).replace("$clog2", "clog2").replace("/", "//")
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError:
        raise HardwareError(f"{text!r} is not a constant expression hetros evaluates") from None

    def value(node: ast.AST) -> int:
        if isinstance(node, ast.Constant) and isinstance(node.value, int):
            return node.value
        if isinstance(node, ast.Name) and node.id in values:
            return values[node.id]
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
            inner = value(node.operand)
            return -inner if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
            try:
                return int(_OPERATORS[type(node.op)](value(node.left), value(node.right)))
            except (ZeroDivisionError, ValueError, OverflowError) as exc:
                raise HardwareError(f"{text!r} cannot be evaluated: {exc}") from None
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "clog2" and \
                len(node.args) == 1:
            argument = value(node.args[0])
            return 0 if argument <= 1 else math.ceil(math.log2(argument))
        name = node.id if isinstance(node, ast.Name) else ast.unparse(node)
        raise HardwareError(f"{text!r} uses {name}, which hetros cannot evaluate (a parameter of the module, a "
                            "number, + - * / % << >> ** or $clog2)")

    return value(tree.body)


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
                ports[port] = VerilogPort(port, direction, width, high, low)
    parameters = tuple(re.findall(r"\bparameter\b\s*(?:integer|int)?\s*(?:\[[^\]]*\])?\s*([A-Za-z_]\w*)", body))
    defaults = tuple((n, v.strip()) for n, v in re.findall(
        r"\bparameter\b\s*(?:integer|int)?\s*(?:\[[^\]]*\])?\s*([A-Za-z_]\w*)\s*=\s*([^,;)]+)", body))
    return VerilogModule(path, name, ports, parameters, defaults)


class VerilogNode(wiring.Component):
    """A Verilog module as a hardware node: one ``In``/``Out(axi_stream(data_width))`` member per stream
    port it has, found from its ``<port>_tdata`` ports (see the module's docstring)."""

    def __init__(self, module: VerilogModule, data_width: int, parameters: dict[str, Any]) -> None:
        self.module = module
        self.data_width = data_width
        self.parameters = {k: v for k, v in parameters.items() if k in module.parameters}
        values = module.parameter_values(self.parameters)  # the ports' ranges as this node elaborates them
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
            for field, bits in (("tdata", data_width), ("tkeep", data_width // 8), ("tlast", 1), ("tvalid", 1),
                                ("tready", 1)):
                declared = self._streams[stream][field]
                try:
                    width = declared.width_with(values)
                except HardwareError as exc:
                    raise HardwareError(f"hw: {module.path}:{module.name}: the width of {declared.name} "
                                        f"[{declared.high}:{declared.low}]: {exc}") from None
                if width != bits:
                    shown = f"[{declared.high}:{declared.low}]" if declared.high else "1 bit"
                    given = ", ".join(f"{k} = {v}" for k, v in values.items() if k in f"{declared.high} {declared.low}")
                    raise HardwareError(
                        f"hw: {module.path}:{module.name}: {declared.name} is {width} bits ({shown}"
                        f"{' with ' + given if given else ''}), but must be {bits} for the target's data_width "
                        f"{data_width}: set the module's parameters in the node's parameters, or fix the port")
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
