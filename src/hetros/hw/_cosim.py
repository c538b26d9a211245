"""Co-simulation: an fpga target's hardware running in a simulator process of the graph.

The planner gives each fpga target whose topics cross to software a gateway node (see
``plan.gateway_node``) in a process of the target's own. That node runs :func:`gateway`: it
builds the target's top module (its hardware nodes and topic networks, ``_build``), has
Verilator compile it once (``_verilator``), and then moves messages between the graph and
the simulated ports. What software publishes to the hardware arrives through the
gateway's ordinary subscriptions (shared memory from other processes of the host) and is
pushed into the top's ``s_axis`` port as its CDR body; what the hardware publishes comes
out of an ``m_axis`` port and is published as an ordinary message. Software nodes cannot
tell a hardware peer from a software one.

Reliable topics stay lossless across the gateway: it takes from a subscription only while
the port's queue has room, so a full hardware side fills the subscription's FIFO and then
blocks the software publisher, as any slow subscriber would; and the hardware's output
port holds TREADY low while the gateway's publisher is blocked.
"""

from __future__ import annotations

import hashlib
import json
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._errors import HardwareError
from .._log import get_logger
from ..msg import TypeRegistry
from ..plan import Plan, gateway_node
from ._build import FpgaTop, HardwareTopic, hardware_nodes, hardware_topics, top_name
from ._verilator import IDLE, StreamPort, VerilatedTop, compile_simulator

if TYPE_CHECKING:
    from ..runtime import Node

log = get_logger("hetros.cosim")

# messages a gateway keeps queued at an input port: enough that the hardware never waits for Python
# between two messages, few enough that back-pressure reaches the publisher early
_QUEUED = 2
# cycles a run may take before Python looks at the graph again, and quiet cycles after which a design
# whose inputs are empty counts as idle (the gateway then sleeps until software publishes)
_CHUNK = 2_000_000
_IDLE_CYCLES = 20_000


@dataclass(frozen=True)
class GatewayPort:
    """One end of a gateway at the top module: the topic, its type and the port's index."""

    topic: str
    type: str
    index: int
    port: StreamPort


class TargetSimulation:
    """An fpga target's top module compiled and instantiated: the gateway's view of the hardware."""

    def __init__(self, plan: Plan, target: str, types: TypeRegistry) -> None:
        from amaranth.back import verilog

        spec = plan.targets[target]
        self.target, self.clock_mhz = target, spec.clock_mhz
        gateway = gateway_node(target)
        topics = hardware_topics(plan, target)
        top = FpgaTop(topics, spec.data_width, hardware_nodes(plan, target), monitor=True)
        name = top_name(target)
        text = verilog.convert(top, name=name, ports=top.signals())
        clocked = re.search(r"\binput\s+clk\b", text) is not None
        ports = []
        self.inputs: list[GatewayPort] = []
        self.outputs: list[GatewayPort] = []
        for prefix in top.ports:
            topic, node, feeds = top.endpoint_of(prefix)
            if node != gateway:
                raise HardwareError(f"fpga target {target}: node {node} on {topic.name} has no hw: implementation, so "
                                    "nothing can run it in the simulator; give it one (hw: module:Component) or move "
                                    "it to a process target")
            peers = [n for n in (topic.subscribers if feeds else topic.publishers) if n != gateway]
            label = (f"gateway of {target}, software -> {', '.join(peers)} on {topic.name} (port {prefix})" if feeds
                     else f"gateway of {target}, {', '.join(peers)} -> software on {topic.name} (port {prefix})")
            port = StreamPort(prefix, feeds, label)
            ports.append(port)
            into = self.inputs if feeds else self.outputs
            into.append(GatewayPort(topic.name, topic.type, len(into), port))
        started = time.perf_counter()
        library = compile_simulator(text, name, ports, spec.data_width, clocked, design_key(plan, target, topics),
                                    top.monitored)
        self.compile_seconds = time.perf_counter() - started
        self.top = VerilatedTop(library, ports)

    def close(self) -> None:
        self.top.close()


# simulations built before the graph started (``gateway.prepare``), by gateway node
_PREPARED: dict[str, TargetSimulation] = {}


def _prepare(plan: Plan, name: str, types: TypeRegistry) -> None:
    """Build and compile the target's simulation while the process starts, before the graph goes, so the
    first messages meet a running simulator (and compile time is not the publishers' wait)."""
    _PREPARED[name] = TargetSimulation(plan, plan.nodes[name].target, types)


def design_key(plan: Plan, target: str, topics: list[HardwareTopic]) -> str:
    """What the target's hardware is made of, as sources: its nodes' ``hw:`` and parameters, its topics,
    the target's stream width, Amaranth's version, and the text of hetros's hardware modules and of every
    Python file of the project folder and of each hardware node's module."""
    import amaranth

    spec = plan.targets[target]
    parts = [amaranth.__version__, str(spec.data_width), repr(topics)]
    files = sorted(Path(__file__).parent.glob("*.py")) + sorted(Path(plan.root).rglob("*.py"))
    for name, node in sorted(plan.nodes.items()):
        if node.target == target and plan.in_hardware(name):
            parts.append(f"{name}={node.hw}:{json.dumps(node.parameters, sort_keys=True, default=str)}")
            module = sys.modules.get(node.hw.partition(":")[0])
            source = getattr(module, "__file__", None)
            if source:
                files.append(Path(source))
    digest = hashlib.sha256("\0".join(parts).encode())
    for path in files:
        if ".venv" not in path.parts and path.is_file():
            digest.update(str(path).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def gateway(node: Node) -> None:
    """The gateway node of an fpga target: its hardware in Verilator, its topics in the graph."""
    plan = node.graph.plan
    if plan is None:
        raise HardwareError("a gateway runs inside a launch: it needs the plan of the project")
    target = str(node.get_parameter("target"))
    types = node.graph.types
    simulation = _PREPARED.pop(node.name, None) or TargetSimulation(plan, target, types)
    top = simulation.top
    log.info("fpga target %s in verilator (%d gateway ports; compiled or found in the cache in %.1f s)", target,
             len(top.inputs) + len(top.outputs), simulation.compile_seconds)
    inputs = []
    for port in simulation.inputs:
        codec = types.codec(port.type)
        inputs.append((port, node.create_subscription(types.get(port.type), port.topic), codec))
    outputs = []
    for port in simulation.outputs:
        codec = types.codec(port.type)
        outputs.append((port, node.create_publisher(types.get(port.type), port.topic), codec))
    stop = node.graph.stop
    wall = 0.0
    try:
        while not stop.is_set():
            seen = node.executor.generation
            for port, subscription, codec in inputs:
                while top.queued(port.index) < _QUEUED:
                    message = subscription.try_take()
                    if message is None:
                        break
                    encoded = bytearray(codec.size(message))
                    codec.encode(message, memoryview(encoded))
                    top.push(port.index, bytes(encoded))
            started = time.perf_counter()
            events = top.run(_CHUNK, _IDLE_CYCLES)
            wall += time.perf_counter() - started
            for port, publisher, codec in outputs:
                while (produced := top.pop(port.index)) is not None:
                    publisher.publish(codec.decode(memoryview(produced)))
            waiting = any(top.queued(p.index) for p, _, _ in inputs)
            if events & IDLE and not waiting:
                node.executor.wait(seen, 0.1)
    finally:
        _report(simulation, wall)
        for port in simulation.outputs:
            partial = top.partial(port.index)
            if partial:
                log.error("%s: %d bytes arrived without TLAST ending their message", port.port.label, partial)
        simulation.close()


gateway.prepare = _prepare  # type: ignore[attr-defined]


def _report(simulation: TargetSimulation, wall: float) -> None:
    """Simulated time beside wall time: per gateway port, cycles per message and µs at the target clock."""
    top = simulation.top
    cycles = top.cycle
    rate = cycles / wall if wall > 0 else 0.0
    log.info("fpga target %s: %d cycles simulated (%.3f ms at %g MHz) in %.3f s of simulation (%.2f M cycles/s)",
             simulation.target, cycles, cycles / simulation.clock_mhz / 1000, simulation.clock_mhz, wall, rate / 1e6)
    for output, ports in ((False, simulation.inputs), (True, simulation.outputs)):
        for port in ports:
            messages, beats, busy = top.stats(output, port.index)
            if messages:
                per = busy / messages
                log.info("  %s: %d messages, %d beats, %.0f cycles per message (%.2f µs at %g MHz)", port.port.label,
                         messages, beats, per, per / simulation.clock_mhz, simulation.clock_mhz)


def gateway_statistics(simulation: TargetSimulation) -> list[dict[str, Any]]:
    """Per gateway port: topic, direction, messages, beats and busy cycles (for reports and benchmarks)."""
    rows = []
    for output, ports in ((False, simulation.inputs), (True, simulation.outputs)):
        for port in ports:
            messages, beats, busy = simulation.top.stats(output, port.index)
            rows.append({"topic": port.topic, "direction": "hardware -> software" if output else
                         "software -> hardware", "messages": messages, "beats": beats, "busy_cycles": busy})
    return rows
