"""An fpga target's topic network as one Verilog top module, and a manifest of its ports.

Every hardware topic of the target becomes a :class:`TopicNetwork`; the top module exposes
each endpoint as an AXI4-Stream port with vendor-conventional names, so Vivado and
friends infer the interfaces: ``s_axis_<topic>_<node>_*`` where a publishing node feeds
the network, ``m_axis_<topic>_<node>_*`` where a subscribing node is fed. ``clk`` is the
clock, ``rst`` an active-high synchronous reset.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from amaranth import Cat, Module, Signal
from amaranth.back import verilog
from amaranth.hdl import Elaboratable
from amaranth.lib import wiring

from ..._errors import HardwareError
from ...msg import TypeRegistry, flat_layout
from ...plan import Plan, gateway_node
from ..designs._verilog_node import verilog_sources
from ..streams._axi import TopicNetwork
from ..streams._ports import port_part, service_ports

_FIELDS = (("tdata", None), ("tkeep", None), ("tlast", 1), ("tvalid", 1), ("tready", 1))
# the endpoint of a topic the target frames for ROS 1 itself (hardware TCPROS, ``_tcpros``): its port
# carries TCPROS frames (``m_axis_<topic>_tcpros`` to ROS 1 subscribers, ``s_axis_<topic>_tcpros`` from a
# ROS 1 publisher), moved to and from the sockets unchanged by the gateway
TCPROS = "tcpros"
_HELD_RULE = "TVALID dropped, or TDATA/TKEEP/TLAST changed, before TREADY"


@dataclass(frozen=True)
class HardwareTopic:
    """A topic all of whose endpoints sit on one fpga target."""

    name: str
    type: str
    publishers: tuple[str, ...]
    subscribers: tuple[str, ...]
    fifo_depth: int | None
    # a service's requests (into its hardware server) or responses (out of it): the service's name
    service: str = ""
    response: bool = False

    @property
    def port_name(self) -> str:
        if self.service:
            return service_ports(self.service)[1 if self.response else 0]
        return port_part(self.name)


def hardware_topics(plan: Plan, target: str, only: set[str] | None = None) -> list[HardwareTopic]:
    """The hardware topics of ``target``, in the plan's order.

    A topic's network connects the target's nodes on it and, where the topic crosses to software,
    the target's gateway: as a publisher into the network where software (or a node off the
    design) publishes to the hardware, as a subscriber of it where software subscribes. With
    ``only``, the design holds just those hardware nodes and the target's others count as
    software: each node behind a gateway of its own, as ``hw report`` compares.
    """
    if target not in plan.targets or plan.targets[target].kind != "fpga":
        fpga = [t.name for t in plan.targets.values() if t.kind == "fpga"]
        raise HardwareError(f"target must be an fpga target of the project ({', '.join(fpga) or 'none'}), "
                            f"not {target!r}")
    gateway = gateway_node(target)
    spec = plan.targets[target]

    def inside(node: str) -> bool:
        return node != gateway and plan.nodes[node].target == target and (only is None or node in only)

    topics = []
    for channel in plan.channels.values():
        if channel.kind == "reply":
            continue  # a hardware server's responses: one stream per service, below
        sources = [n for n in channel.publishers if n != gateway]
        sinks = [n for n in channel.subscribers if n != gateway]
        publishers = tuple(n for n in sources if inside(n))
        subscribers = tuple(n for n in sinks if inside(n))
        if subscribers and any(not inside(n) for n in sources):
            publishers += (gateway,)
        if publishers and publishers != (gateway,) and \
                (gateway in channel.publishers or any(not inside(n) for n in sinks)):
            subscribers += (gateway,)
        if channel.kind == "topic" and only is None:
            if channel.name in spec.ros1_export and any(inside(n) for n in sources):
                subscribers += (TCPROS,)
            if channel.name in spec.ros1_import and any(inside(n) for n in sinks):
                publishers += (TCPROS,)
        if not publishers or not subscribers or publishers == subscribers == (gateway,):
            continue  # an endpoint with nobody on the other side has nothing to wire
        topics.append(HardwareTopic(channel.name, channel.type, publishers, subscribers, channel.qos.hw_fifo,
                                    channel.service))
        if channel.kind == "request":
            response = channel.type.removesuffix("_Request") + "_Response"
            topics.append(HardwareTopic(f"{channel.service} (responses)", response, subscribers, publishers,
                                        channel.qos.hw_fifo, channel.service, response=True))
    names: dict[str, str] = {}
    for topic in topics:
        other = names.setdefault(topic.port_name, topic.name)
        if other != topic.name:
            raise HardwareError(f"topics {other} and {topic.name} both become port names *_{topic.port_name}_*; "
                                "rename one")
    return topics


class FpgaTop(Elaboratable):
    """The top module: every hardware topic of one fpga target; each endpoint is wired to its node's
    hardware implementation where the node has one, else behind an AXI4-Stream port of the top."""

    def __init__(self, topics: list[HardwareTopic], data_width: int,
                 hardware_nodes: dict[str, Elaboratable] | None = None, monitor: bool = False,
                 framing: dict[str, Any] | None = None, max_frame: int = 4096) -> None:
        self.topics = topics
        self.data_width = data_width
        self.hardware_nodes = dict(hardware_nodes or {})
        # hardware TCPROS: topic -> its ``Ros1Program``, for the topics with a TCPROS endpoint
        self.framing = dict(framing or {})
        self.max_frame = max_frame
        # (port prefix, topic index, "pub"/"sub", endpoint index) -> signals by field
        self.ports: dict[str, dict[str, Any]] = {}
        self._where: dict[str, tuple[int, str, int]] = {}
        # (node, topic index, "pub"/"sub", endpoint index) of endpoints inside the top
        self._inside: list[tuple[str, int, str, int]] = []
        for index, topic in enumerate(topics):
            for role, nodes, prefix in (("pub", topic.publishers, "s_axis"), ("sub", topic.subscribers, "m_axis")):
                for position, node in enumerate(nodes):
                    if node in self.hardware_nodes:
                        self._inside.append((node, index, role, position))
                        continue
                    name = f"{prefix}_{topic.port_name}_{node}"
                    self.ports[name] = {
                        field: Signal(width or (data_width if field == "tdata" else data_width // 8),
                                      name=f"{name}_{field}")
                        for field, width in _FIELDS}
                    self._where[name] = (index, role, position)
        # with ``monitor`` (co-simulation), each stream a hardware node drives is watched for the AXI4-Stream
        # rule (once TVALID is shown, it and the payload hold until TREADY): bit k of ``violations`` is
        # ``monitored[k]`` breaking it this cycle
        self.monitored = [(f"hardware node {node} port {topics[index].port_name!r} ({topics[index].name})", _HELD_RULE)
                          for node, index, role, _ in self._inside if role == "pub"] if monitor else []
        for topic in topics:
            for role, nodes in (("pub", topic.publishers), ("sub", topic.subscribers)):
                if TCPROS in nodes and topic.name not in self.framing:
                    raise HardwareError(f"{topic.name} is framed for ROS 1 in hardware, but no program was given")
                if TCPROS in nodes and monitor:
                    longer = (f" (or held more than {max_frame} bytes before its last string or sequence: raise the "
                              "target's tcpros_frame_bytes)")
                    self.monitored.append((
                        f"hardware TCPROS of {topic.name} ({'from' if role == 'pub' else 'to'} ROS 1)",
                        "a message did not fit its type" + (longer if role == "sub" else "")))
        if len(self.monitored) > 64:
            raise HardwareError(f"co-simulation watches at most 64 hardware node outputs, not {len(self.monitored)}")
        self.violations = Signal(max(1, len(self.monitored)), name="hw_violations")
        # hardware nodes reading messages in memory: their AXI4 port ``mem`` as the top's ``m_axi_<node>_*``
        from ..designs._memory import MEMORY_PORT

        self.memory_ports: dict[str, dict[str, Any]] = {}
        for node, component in self.hardware_nodes.items():
            members = dict(component.signature.members.items())
            if MEMORY_PORT in members:
                port = getattr(component, MEMORY_PORT)
                self.memory_ports[node] = {name: Signal(len(getattr(port, name)), name=f"m_axi_{node}_{name}")
                                           for name in members[MEMORY_PORT].signature.members}

    def endpoint_of(self, prefix: str) -> tuple[HardwareTopic, str, bool]:
        """``(topic, node, feeds the network)`` of an external port (``s_axis_...`` or ``m_axis_...``)."""
        index, role, position = self._where[prefix]
        topic = self.topics[index]
        nodes = topic.publishers if role == "pub" else topic.subscribers
        return topic, nodes[position], role == "pub"

    def signals(self) -> list[Any]:
        streams = [signal for port in self.ports.values() for signal in port.values()]
        streams += [signal for port in self.memory_ports.values() for signal in port.values()]
        return streams + ([self.violations] if self.monitored else [])

    def elaborate(self, platform: object) -> Module:
        m = Module()
        networks = []
        for topic in self.topics:
            network = TopicNetwork(len(topic.publishers), len(topic.subscribers), self.data_width,
                                   topic.fifo_depth)
            m.submodules[f"topic_{topic.port_name}"] = network
            networks.append(network)
        framing_errors = []
        for name, port in self.ports.items():
            index, role, position = self._where[name]
            stream = getattr(networks[index], f"{role}{position}")
            topic = self.topics[index]
            if name.endswith(f"_{TCPROS}") and (topic.publishers if role == "pub" else topic.subscribers)[position] \
                    == TCPROS:
                stream, malformed = self._framer(m, topic, role, stream)
                framing_errors.append(malformed)
            if role == "pub":  # the node drives the network's input
                m.d.comb += [getattr(stream, f).eq(port[f]) for f in ("tdata", "tkeep", "tlast", "tvalid")]
                m.d.comb += port["tready"].eq(stream.tready)
            else:
                m.d.comb += [port[f].eq(getattr(stream, f)) for f in ("tdata", "tkeep", "tlast", "tvalid")]
                m.d.comb += stream.tready.eq(port["tready"])
        for node, component in self.hardware_nodes.items():
            m.submodules[f"node_{node}"] = component
        for node, signals in self.memory_ports.items():
            from ..designs._memory import MEMORY_PORT

            port = getattr(self.hardware_nodes[node], MEMORY_PORT)
            flows = dict(self.hardware_nodes[node].signature.members[MEMORY_PORT].signature.members.items())
            for name, top_signal in signals.items():
                if flows[name].flow == wiring.Out:  # the node drives it
                    m.d.comb += top_signal.eq(getattr(port, name))
                else:
                    m.d.comb += getattr(port, name).eq(top_signal)
        for node, index, role, position in self._inside:
            stream = getattr(networks[index], f"{role}{position}")
            port = getattr(self.hardware_nodes[node], self.topics[index].port_name)
            if role == "pub":  # the hardware node drives the network's input
                wiring.connect(m, port, stream)
            else:
                wiring.connect(m, stream, port)
        if self.monitored:
            bits = [_held_stream_broken(m, getattr(self.hardware_nodes[node], self.topics[index].port_name))
                    for node, index, role, _ in self._inside if role == "pub"]
            m.d.comb += self.violations.eq(Cat(*bits, *framing_errors))
        return m

    def _framer(self, m: Module, topic: HardwareTopic, role: str, stream: Any) -> tuple[Any, Signal]:
        """Put a TCPROS framer (to ROS 1) or deframer (from it) between ``stream`` and the port; the
        stream the port now meets, and the unit's ``malformed``."""
        from ..designs._tcpros import Ros1Deframer, Ros1Framer

        program = self.framing[topic.name]
        if role == "pub":  # frames from a ROS 1 publisher into the network
            deframer = Ros1Deframer(program, self.data_width)
            m.submodules[f"tcpros_in_{topic.port_name}"] = deframer
            wiring.connect(m, deframer.cdr, stream)
            return deframer.frame, deframer.malformed
        framer = Ros1Framer(program, self.data_width, self.max_frame)
        m.submodules[f"tcpros_out_{topic.port_name}"] = framer
        wiring.connect(m, stream, framer.cdr)
        return framer.frame, framer.malformed


def _held_stream_broken(m: Module, port: Any) -> Signal:
    """High in a cycle where ``port`` takes TVALID back, or changes its payload, before TREADY took the beat."""
    held = Signal()
    previous = Signal(len(port.tdata) + len(port.tkeep) + 1)
    payload = Cat(port.tdata, port.tkeep, port.tlast)
    broken = Signal()
    m.d.sync += [held.eq(port.tvalid & ~port.tready), previous.eq(payload)]
    m.d.comb += broken.eq(held & (~port.tvalid | (payload != previous)))
    return broken


def hardware_nodes(plan: Plan, target: str, only: set[str] | None = None) -> dict[str, Elaboratable]:
    """The hardware implementations of ``target``'s nodes that have one (of ``only``, when given), elaborated
    and their ports checked against the node's topics."""
    from ..nodes import make_hardware_node, port_problems

    made: dict[str, Elaboratable] = {}
    width = plan.targets[target].data_width
    for name, node in plan.nodes.items():
        wanted = only is None or name in only
        if node.target != target or not node.hw or not plan.in_hardware(name) or not wanted:
            continue
        component = make_hardware_node(node.hw, plan.root, width, node.parameters)
        problems = port_problems(component, list(node.publish), list(node.subscribe), width, list(node.services),
                                 memory=bool(node.memory))
        if problems:
            raise HardwareError(f"node {name}'s hardware ({node.hw}) does not fit its topics: " + "; ".join(problems))
        made[name] = component
    return made


def framing_programs(topics: list[HardwareTopic], types: TypeRegistry) -> dict[str, Any]:
    """The hardware TCPROS program (``_tcpros.Ros1Program``) of each topic with a TCPROS endpoint."""
    from ..designs._tcpros import ros1_program

    return {t.name: ros1_program(types, t.type) for t in topics if TCPROS in (*t.publishers, *t.subscribers)}


def top_name(target: str) -> str:
    return f"hetros_{port_part(target)}"


def build(plan: Plan, target: str, out: Path, types: TypeRegistry) -> tuple[Path, Path]:
    """Write ``<top>.v`` and ``<top>.json`` (the manifest) for ``target`` into ``out``."""
    topics = hardware_topics(plan, target)
    if not topics:
        raise HardwareError(f"fpga target {target!r} has no hardware topic (one with a publisher and a "
                            "subscriber on it, counting its gateway): nothing to generate")
    spec = plan.targets[target]
    components = hardware_nodes(plan, target)
    top = FpgaTop(topics, spec.data_width, components, framing=framing_programs(topics, types),
                  max_frame=spec.tcpros_frame_bytes)
    name = top_name(target)
    text = verilog.convert(top, name=name, ports=top.signals())
    out.mkdir(parents=True, exist_ok=True)
    for source in verilog_sources(components):  # the top instantiates them: they travel with it
        (out / source.name).write_text(source.read_text(encoding="utf-8"))
    verilog_path = out / f"{name}.v"
    verilog_path.write_text(text)
    manifest_path = out / f"{name}.json"
    clocked = re.search(r"\binput\s+clk\b", text) is not None  # what the design uses, hardware nodes included
    described = manifest(plan, target, topics, types, clocked)
    described["verilog_sources"] = [source.name for source in verilog_sources(components)]
    described["memory_masters"] = [{"interface": f"m_axi_{node}", "node": node} for node in top.memory_ports]
    for node, signals in top.memory_ports.items():  # the AXI4 masters of nodes reading messages in memory
        from ..designs._memory import MEMORY_PORT

        flows = components[node].signature.members[MEMORY_PORT].signature.members
        described["ports"] += [{"name": f"m_axi_{node}_{name}", "width": len(signal), "node": node,
                                "direction": "output" if flows[name].flow == wiring.Out else "input",
                                "interface": f"m_axi_{node}", "role": "AXI4 master (memory:)"}
                               for name, signal in signals.items()]
    manifest_path.write_text(json.dumps(described, indent=1))
    return verilog_path, manifest_path


def manifest(plan: Plan, target: str, topics: list[HardwareTopic], types: TypeRegistry,
             clocked: bool) -> dict[str, Any]:
    """Every port with its direction and width, every topic with its endpoints and message layout."""
    spec = plan.targets[target]
    width = spec.data_width
    ports = [{"name": "clk", "direction": "input", "width": 1, "role": "clock"},
             {"name": "rst", "direction": "input", "width": 1, "role": "reset (active high, synchronous)"}
             ] if clocked else []  # a network of wiring only has neither
    for topic in topics:
        for prefix, nodes, sends in (("s_axis", topic.publishers, True), ("m_axis", topic.subscribers, False)):
            for node in nodes:
                if node in plan.nodes and plan.nodes[node].hw and plan.in_hardware(node):
                    continue  # wired to the node's hardware inside the top
                for field, bits in _FIELDS:
                    into_network = (field == "tready") != sends
                    ports.append({"name": f"{prefix}_{topic.port_name}_{node}_{field}",
                                  "direction": "input" if into_network else "output",
                                  "width": bits or (width if field == "tdata" else width // 8),
                                  "topic": topic.name, "node": node,
                                  "interface": f"{prefix}_{topic.port_name}_{node}"})
    layout = {
        topic.name: [{"field": f.path, "type": f.type + (f"[{f.count}]" if f.count > 1 else ""),
                      "offset": f.offset, "size": f.size} for f in flat_layout(types, topic.type).fields]
        for topic in topics}
    return {
        "top": top_name(target), "target": target, "part": spec.part, "clock_mhz": spec.clock_mhz,
        "data_width": width,
        "beats": ("each message is its CDR body (little endian, no encapsulation header) cut into data_width "
                  "beats, byte k of a beat at tdata[8k+7:8k]; tlast on the last beat, tkeep marks its bytes"),
        "ports": ports,
        "hardware_nodes": {name: node.hw for name, node in plan.nodes.items() if node.target == target and node.hw},
        "topics": [{"name": t.name, "type": t.type, "publishers": list(t.publishers),
                    "subscribers": list(t.subscribers), "fifo_depth": t.fifo_depth,
                    "arbiter": len(t.publishers) > 1, "broadcast": len(t.subscribers) > 1,
                    "tcpros": ("frames to ROS 1" if TCPROS in t.subscribers else
                               "frames from ROS 1" if TCPROS in t.publishers else ""),
                    "layout": layout[t.name]} for t in topics],
    }
