"""Hardware nodes: a node's implementation as an Amaranth component on an fpga target.

A public module of its own (``hetros.hw.nodes``), unlike the rest of ``hetros.hw``: a user's
hardware code imports Amaranth anyway, and the reference nodes (``Echo``) are meant to be reused.

A node may name, beside ``run:`` (Python), ``hw:``: a ``module:Component`` (an Amaranth
``wiring.Component`` class, or a function returning one) whose stream ports are named after
the node's topics (``/image_raw`` -> ``image_raw``, as the top module's port names): an ``In``
AXI4-Stream for each topic it subscribes, an ``Out`` one for each it publishes, in the beat
format of hardware topics (the CDR body, ``data_width`` bits a beat). It is called with
``data_width`` and those of the node's ``parameters`` its signature takes (image sizes,
thresholds), so they reach the hardware as elaboration parameters.
"""

from __future__ import annotations

import importlib
import inspect
import sys
from collections.abc import Callable
from typing import Any

from amaranth import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .._errors import HardwareError
from ._build import port_part
from ._image import GaussianBlur, ImageFilter3x3, Sobel
from ._stream import axi_stream

__all__ = ["Echo", "GaussianBlur", "ImageFilter3x3", "NodeUnderTest", "Sobel", "axi_stream", "make_hardware_node",
           "port_problems"]


def make_hardware_node(hw: str, root: str, data_width: int, parameters: dict[str, Any]) -> wiring.Component:
    """The component ``hw`` names, elaborated for ``data_width`` and the node's parameters."""
    module_name, _, attr = hw.partition(":")
    if root not in sys.path:
        sys.path.insert(0, root)
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise HardwareError(f"hw: {hw}: cannot import {module_name!r} ({exc})") from exc
    factory: Callable[..., Any] | None = getattr(module, attr, None)
    if not callable(factory):
        raise HardwareError(f"hw: {hw}: {module_name!r} has no component or function {attr!r}")
    accepted = inspect.signature(factory).parameters
    takes_all = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in accepted.values())
    arguments = {k: v for k, v in {"data_width": data_width, **parameters}.items() if takes_all or k in accepted}
    made = factory(**arguments)
    if not isinstance(made, wiring.Component):
        raise HardwareError(f"hw: {hw} must be an Amaranth wiring.Component (or make one), "
                            f"not {type(made).__name__}")
    return made


def port_problems(component: wiring.Component, publish: list[str], subscribe: list[str],
                  data_width: int) -> list[str]:
    """What keeps ``component`` from serving these topics: each missing, extra or mis-shaped port."""
    wanted = {port_part(t): (Out, t) for t in publish} | {port_part(t): (In, t) for t in subscribe}
    members = dict(component.signature.members.items())
    problems = []
    for name, (flow, topic) in sorted(wanted.items()):
        role = "publishes" if flow is Out else "subscribes"
        member = members.get(name)
        expected = flow(axi_stream(data_width))
        if member is None:
            problems.append(f"port {name!r} is missing: the node {role} {topic}, so its component needs "
                            f"{'Out' if flow is Out else 'In'}(axi_stream({data_width})) named {name!r}")
        elif member != expected:
            problems.append(f"port {name!r} must be {'Out' if flow is Out else 'In'}(axi_stream({data_width})) "
                            f"for {topic}, not {member!r}")
    for name in sorted(set(members) - set(wanted)):
        problems.append(f"port {name!r} is not one of the node's topics ({', '.join(sorted(wanted)) or 'none'}); "
                        "declare the topic or remove the port")
    return problems


class Echo(wiring.Component):
    """A hardware node that republishes every message it receives, beat for beat (ping-pong's echo)."""

    def __init__(self, source: str, sink: str, data_width: int = 64) -> None:
        super().__init__({port_part(source): In(axi_stream(data_width)), port_part(sink): Out(axi_stream(data_width))})
        self._source, self._sink = port_part(source), port_part(sink)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        # inside the component both ports are seen from within: the input's payload drives the output's
        wiring.connect(m, wiring.flipped(getattr(self, self._source)), wiring.flipped(getattr(self, self._sink)))
        return m


class NodeUnderTest(wiring.Component):
    """A hardware node with its input ports as ``pub<i>`` and output ports as ``sub<j>``, the shape the
    topic-network simulation drives (publishers feed it, subscribers take from it)."""

    def __init__(self, node: wiring.Component, inputs: list[str], outputs: list[str], data_width: int,
                 name: str = "") -> None:
        self.node, self.inputs, self.outputs = node, inputs, outputs
        # what the simulation's errors call each output: the node and its port
        self.output_labels = [f"hardware node {name or type(node).__name__} port {port!r}" for port in outputs]
        self.publishers, self.subscribers, self.data_width = len(inputs), len(outputs), data_width
        members = {f"pub{i}": In(axi_stream(data_width)) for i in range(len(inputs))}
        members |= {f"sub{j}": Out(axi_stream(data_width)) for j in range(len(outputs))}
        super().__init__(members)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        m.submodules.node = self.node
        for i, port in enumerate(self.inputs):
            wiring.connect(m, wiring.flipped(getattr(self, f"pub{i}")), getattr(self.node, port))
        for j, port in enumerate(self.outputs):
            wiring.connect(m, getattr(self.node, port), wiring.flipped(getattr(self, f"sub{j}")))
        return m
