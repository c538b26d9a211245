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
from collections.abc import Callable, Sequence
from typing import Any

from amaranth import Cat, Module, Mux
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .._errors import HardwareError
from .designs._image import Compensation, GaussianBlur, ImageFilter3x3, Sobel
from .designs._memory import MemorySobel, axi4_memory
from .designs._sort import Sorter
from .designs._verilog_node import VerilogNode, is_verilog, make_verilog_node
from .designs._walker import FieldWalker, label_bytes
from .streams._axi import axi_stream
from .streams._ports import port_part, service_ports

__all__ = ["AddTwoInts", "Compensation", "Echo", "FieldWalker", "FixedServer", "GaussianBlur", "ImageFilter3x3",
           "MemorySobel", "NodeUnderTest", "Sobel", "Sorter", "VerilogNode", "axi4_memory", "axi_stream",
           "label_bytes", "make_hardware_node", "port_problems"]


def make_hardware_node(hw: str, root: str, data_width: int, parameters: dict[str, Any]) -> wiring.Component:
    """The component ``hw`` names, elaborated for ``data_width`` and the node's parameters (a ``file.v:module``
    is a Verilog module, see ``hetros.hw.designs._verilog_node``)."""
    if is_verilog(hw):
        return make_verilog_node(hw, root, data_width, parameters)
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
                  data_width: int, services: Sequence[str] = (), memory: bool = False) -> list[str]:
    """What keeps ``component`` from serving these topics and services: each missing, extra or mis-shaped
    port. A service it serves is two ports: ``<service>_request`` in, ``<service>_response`` out. A node
    with ``memory:`` has its AXI4 port ``mem`` too."""
    wanted = {port_part(t): (Out, t) for t in publish} | {port_part(t): (In, t) for t in subscribe}
    for service in services:
        request, response = service_ports(service)
        wanted |= {request: (In, f"{service}'s requests"), response: (Out, f"{service}'s responses")}
    members = dict(component.signature.members.items())
    problems = []
    if memory:
        from .designs._memory import MEMORY_PORT, axi4_memory

        member = members.pop(MEMORY_PORT, None)
        if member is None or member != Out(axi4_memory(data_width)):
            problems.append(f"port {MEMORY_PORT!r} must be Out(axi4_memory({data_width})): the node reads and writes "
                            f"messages in memory (memory:), not {member!r}")
    for name, (flow, topic) in sorted(wanted.items()):
        role = "publishes" if flow is Out else "subscribes"
        if topic.endswith("'s requests"):
            role = "serves"
            topic = topic.removesuffix("'s requests") + ", so it takes requests"
        elif topic.endswith("'s responses"):
            role = "serves"
            topic = topic.removesuffix("'s responses") + ", so it gives responses"
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


class FixedServer(wiring.Component):
    """A hardware server of a service whose request and response have fixed sizes (no strings or
    sequences): it gathers a request's beats into one register, computes the response from it
    (:meth:`respond`, combinational) and sends it back, one response per request, in order.
    Requests and responses are their CDR bodies, as on every hardware stream."""

    request_bytes = 0
    response_bytes = 0

    def __init__(self, service: str, data_width: int = 64) -> None:
        self._request, self._response = service_ports(service)
        self.data_width = data_width
        super().__init__({self._request: In(axi_stream(data_width)), self._response: Out(axi_stream(data_width))})

    def respond(self, request: Any) -> Any:
        """The response's bytes (``8 * response_bytes`` bits, byte 0 lowest) from the request's."""
        raise NotImplementedError

    def elaborate(self, platform: object) -> Module:
        from amaranth import Signal

        m = Module()
        requests, responses = getattr(self, self._request), getattr(self, self._response)
        per_beat = self.data_width // 8
        request_beats = -(-self.request_bytes // per_beat)
        response_beats = -(-self.response_bytes // per_beat)
        gathered = Signal(request_beats * self.data_width)
        beat = Signal(range(max(request_beats, response_beats) + 1))
        answer = Signal(response_beats * self.data_width)
        answering = Signal()
        m.d.comb += requests.tready.eq(~answering)
        with m.If(requests.tvalid & requests.tready):
            with m.If(beat < request_beats):
                m.d.sync += gathered.word_select(beat, self.data_width).eq(requests.tdata)
            m.d.sync += beat.eq(beat + 1)
            with m.If(requests.tlast):
                merged = Cat(*(Mux(beat == k, requests.tdata, gathered.word_select(k, self.data_width))
                               for k in range(request_beats)))
                m.d.sync += [answer.eq(self.respond(merged[:8 * self.request_bytes])), answering.eq(1), beat.eq(0)]
        last = beat == response_beats - 1
        tail = self.response_bytes - (response_beats - 1) * per_beat
        m.d.comb += [responses.tvalid.eq(answering), responses.tdata.eq(answer.word_select(beat, self.data_width)),
                     responses.tlast.eq(last),
                     responses.tkeep.eq(Mux(last, (1 << tail) - 1, (1 << per_beat) - 1))]
        with m.If(responses.tvalid & responses.tready):
            m.d.sync += beat.eq(beat + 1)
            with m.If(last):
                m.d.sync += [answering.eq(0), beat.eq(0)]
        return m


class AddTwoInts(FixedServer):
    """``example_interfaces/srv/AddTwoInts`` in hardware: ``sum = a + b`` (int64, wrapping)."""

    request_bytes = 16
    response_bytes = 8

    def respond(self, request: Any) -> Any:
        return (request[:64] + request[64:128])[:64]
