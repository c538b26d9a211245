"""Co-simulation: an fpga target's top module (its hardware nodes and topic networks, ``_build``)
compiled by Verilator (``_verilator``), with a port for each end of its gateway.

The gateway node that drives it in a launch is ``hetros.launch.system._gateway``; benchmarks and
tests drive it directly.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass

from ..._errors import HardwareError
from ...msg import TypeRegistry
from ...plan import Plan, gateway_node
from ..designs._verilog_node import verilog_sources
from ..top._build import TCPROS, FpgaTop, framing_programs, hardware_nodes, hardware_topics, top_name
from ..top._clock import design_key, target_clock
from ._amaranth_top import AmaranthTop
from ._verilator import MemoryPort, StreamPort, VerilatedTop, compile_simulator, trace_setting


@dataclass(frozen=True)
class GatewayPort:
    """One end of a gateway at the top module: the topic, its type and the port's index."""

    topic: str  # the channel (a service's request channel for its requests)
    type: str
    index: int
    port: StreamPort
    service: str = ""  # the service whose requests go in, or whose responses come out, here
    ros1: bool = False  # TCPROS frames (hardware TCPROS), to or from ROS 1's sockets
    # the hardware node reads (an input) or writes (an output) this topic's messages in memory: the port
    # carries descriptors in and completions out (``_memory``); its node
    memory_node: str = ""
    # an input's hardware nodes: each may check a message before it goes in (``check_message``)
    readers: tuple[str, ...] = ()


SimulatedTop = VerilatedTop | AmaranthTop


class TargetSimulation:
    """An fpga target's top module compiled and instantiated: the gateway's view of the hardware."""

    def __init__(self, plan: Plan, target: str, types: TypeRegistry, only: set[str] | None = None) -> None:
        from amaranth.back import verilog

        spec = plan.targets[target]
        self.target, self.simulator = target, spec.sim
        gateway = gateway_node(target)
        topics = hardware_topics(plan, target, only)
        components = hardware_nodes(plan, target, only)
        top = FpgaTop(topics, spec.data_width, components, monitor=True, framing=framing_programs(topics, types),
                      max_frame=spec.tcpros_frame_bytes)
        name = top_name(target)
        ports = []
        self.inputs: list[GatewayPort] = []
        self.outputs: list[GatewayPort] = []
        for prefix in top.ports:
            topic, node, feeds = top.endpoint_of(prefix)
            if node == TCPROS:
                label = f"hardware TCPROS of {topic.name}, {'from' if feeds else 'to'} ROS 1 (port {prefix})"
                port = StreamPort(prefix, feeds, label)
                ports.append(port)
                into = self.inputs if feeds else self.outputs
                into.append(GatewayPort(topic.name, topic.type, len(into), port, ros1=True))
                continue
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
            in_memory = [n for n in peers if topic.name in plan.nodes[n].memory]
            into.append(GatewayPort(topic.name, topic.type, len(into), port, topic.service,
                                    memory_node=in_memory[0] if in_memory else "",
                                    readers=tuple(peers) if feeds else ()))
        self.components = components
        self.memories = [MemoryPort(f"m_axi_{node}", f"hardware node {node}'s memory port (mem)")
                         for node in top.memory_ports]
        started = time.perf_counter()
        sources = verilog_sources(components)
        key = design_key(plan, target, topics, sources)
        # the clock the simulated-time figures use: clock_mhz, or the Fmax place and route achieved if lower
        # (measured for the whole target: a part of it, ``only``, is looked up as the whole)
        self.clock = target_clock(plan, target, key if only is None else None)
        self.clock_mhz = self.clock.mhz
        self.top: SimulatedTop
        tracing = trace_setting()
        if spec.sim == "amaranth":
            if sources:
                raise HardwareError(f"fpga target {target}: sim: amaranth cannot run Verilog nodes "
                                    f"({', '.join(s.name for s in sources)}); use sim: verilator")
            if self.memories:
                raise HardwareError(f"fpga target {target}: sim: amaranth has no memory model for nodes reading "
                                    "messages in memory (memory:); use sim: verilator")
            self.top = AmaranthTop(top, ports, spec.data_width, top.monitored)
        else:
            text = verilog.convert(top, name=name, ports=top.signals())
            clocked = re.search(r"\binput\s+clk\b", text) is not None
            library = compile_simulator(text, name, ports, spec.data_width, clocked, key, top.monitored, sources,
                                        memories=self.memories, traced=tracing is not None)
            self.top = VerilatedTop(library, ports)
        if tracing is not None:
            self.top.trace(tracing.folder / target, tracing, self.clock_mhz)
        self.compile_seconds = time.perf_counter() - started

    def close(self) -> None:
        self.top.close()
