"""From a checked project to the plan: one transport per edge, and the bridge nodes."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from .._errors import CheckError
from .._qos import QoS
from ..msg import TypeRegistry, normalize_typename, registry
from ..plan import (
    CLOCK_PREFIX,
    CLOCK_TOPIC,
    CLOCK_TYPE,
    LAUNCHER,
    ROS1_BRIDGE,
    SERVICE_QOS,
    SYSTEM_NODES,
    ChannelPlan,
    EdgePlan,
    HostPlan,
    NodePlan,
    Plan,
    TargetPlan,
    TransportKind,
    action_topic_qos,
    gateway_node,
    process_name,
    reply_channel,
    request_channel,
)
from ._bridges import hardware_framed, ros1_bridge, ros1_master, ros1_nodes, ros2_bridge
from ._checks import check, project_hash
from ._model import LoadedProject, NodeSpec, TargetSpec, load_project


def plan(project: LoadedProject, types: TypeRegistry | None = None) -> Plan:
    """Check, then compute the architecture graph. Raises CheckError with every problem.

    In steps: the channels of every endpoint (topics, service requests and replies), the system
    nodes (bridges, gateways, clock followers), where each node runs (process and host), one
    transport per edge (:func:`edge_transport`), and the plan's tables.
    """
    types = types or registry()
    report = check(project, types)
    if report.errors:
        raise CheckError(report.errors)
    model = project.model
    bridges = [b for b in (ros1_bridge(project), ros2_bridge(project)) if b is not None]
    speaks_ros1 = ros1_nodes(project)
    channels = _channels(project, _endpoints(project, bridges, speaks_ros1))
    process_of = {n: process_name(s.target, model.targets[s.target].kind) for n, s in model.nodes.items()}
    process_of |= {bridge.name: LAUNCHER for bridge in bridges}
    fpga_of = {n: s.target for n, s in model.nodes.items() if model.targets[s.target].kind == "fpga"}
    framed = hardware_framed(project)
    # imported topics an fpga target's hardware receives straight from ROS 1: not again through the bridge
    received_from_ros1 = {(gateway_node(t), topic) for t, (_, imports) in framed.items() for topic in imports}
    gateways = _add_gateways(channels, fpga_of, received_from_ros1)
    gateways |= {gateway_node(t): t for t in framed}  # a target framing ROS 1 topics needs its gateway to run
    process_of |= gateways
    clocks = _clock_followers(project, process_of, fpga_of, speaks_ros1) if model.use_sim_time else {}
    for follower, target in clocks.items():
        process_of[follower] = process_name(target, model.targets[target].kind)
        _add(channels, CLOCK_TOPIC, CLOCK_TYPE, "topic", project, sub=follower)
    # every target on a host: its own, else the first one named (bridges run in the first host's launcher)
    first_host = next(iter(model.hosts), "")
    host_of_target = {t: spec.host or first_host for t, spec in model.targets.items()}
    placement = Placement(
        process_of=process_of, fpga_of=fpga_of, gateways=gateways, received_from_ros1=received_from_ros1,
        host_of={n: host_of_target[s.target] for n, s in model.nodes.items()} | {b.name: first_host for b in bridges}
        | {g: host_of_target[t] for g, t in (gateways | clocks).items()})
    edges = tuple(EdgePlan(c.name, p, s, kind) for c in channels.values() for p in c.publishers
                  for s in c.subscribers if (kind := edge_transport(c.name, p, s, placement)) is not None)
    return _tables(project, channels, edges, bridges, gateways, clocks, host_of_target, framed, speaks_ros1)


def _tables(project: LoadedProject, channels: dict[str, ChannelPlan], edges: tuple[EdgePlan, ...],
            bridges: list[NodePlan], gateways: dict[str, str], clocks: dict[str, str], host_of_target: dict[str, str],
            framed: dict[str, tuple[tuple[str, ...], tuple[str, ...]]], speaks_ros1: set[str]) -> Plan:
    """The last step: the plan's tables from what the steps before found."""
    model = project.model
    first_host = next(iter(model.hosts), "")
    external = model.external
    return Plan(
        name=model.name,
        root=str(project.root.resolve()),
        message_paths=tuple(str((project.root / m).resolve()) for m in model.messages),
        targets={n: _target_plan(n, t, host_of_target[n], framed.get(n, ((), ()))) for n, t in model.targets.items()}
        | {bridge.name: TargetPlan(bridge.name, "thread", host=first_host) for bridge in bridges},
        nodes={n: _node_plan(project, n, s) for n, s in model.nodes.items()}
        | {bridge.name: bridge for bridge in bridges}
        | {g: _gateway_plan(channels, g, t) for g, t in gateways.items()}
        | {c: NodePlan(name=c, run=SYSTEM_NODES["clock_follower"], target=t, subscribe={CLOCK_TOPIC: CLOCK_TYPE})
           for c, t in clocks.items()},
        channels=channels,
        edges=edges,
        ros1_master=ros1_master(project),
        ros1_host=external.ros1.host if external is not None and external.ros1 else "127.0.0.1",
        ros1_qos={t: q for t, q in model.topics.items()
                  if any(t in model.nodes[n].publish or t in model.nodes[n].subscribe for n in speaks_ros1)},
        hosts={n: HostPlan(n, h.address, h.ssh or "") for n, h in model.hosts.items()},
        on_peer_lost=model.on_peer_lost,
        dds_domain=model.dds_domain,
        project_hash=project_hash(project),
        use_sim_time=model.use_sim_time,
        parameters=dict(model.parameters),
        foxglove_hosts=tuple(model.foxglove_hosts),
        python_path=tuple(map(str, project.import_folders[1:])),
    )


# a node's endpoints as the planner reads them: (name, publish, subscribe, services, clients)
_Endpoints = tuple[str, dict[str, str], dict[str, str], dict[str, str], dict[str, str]]


def _endpoints(project: LoadedProject, bridges: list[NodePlan], speaks_ros1: set[str]) -> list[_Endpoints]:
    """Every hetros node's endpoints, the bridges' too (ROS 1 nodes' endpoints are ROS 1's, not channels)."""
    found = [(n, spec.types("publish") | project.lifecycle_events_heard(n), spec.types("subscribe"),
              spec.types("services") | project.parameter_services_called(n), spec.types("clients"))
             for n, spec in project.model.nodes.items() if n not in speaks_ros1]
    return found + [(b.name, b.publish, b.subscribe, b.services, b.clients) for b in bridges]


def _channels(project: LoadedProject, endpoints: list[_Endpoints]) -> dict[str, ChannelPlan]:
    """The channels of the graph: its topics, one request channel per service, one reply channel per client."""
    channels: dict[str, ChannelPlan] = {}
    for nname, publish, subscribe, _services, _clients in endpoints:
        for topic, typename in publish.items():
            _add(channels, topic, normalize_typename(typename), "topic", project, pub=nname)
        for topic, typename in subscribe.items():
            _add(channels, topic, normalize_typename(typename), "topic", project, sub=nname)
    for nname, _publish, _subscribe, services, clients in endpoints:
        for service, typename in services.items():
            srv = normalize_typename(typename, "srv")
            _add(channels, request_channel(service), f"{srv}_Request", "request", project, sub=nname,
                 service=service)
        for service, typename in clients.items():
            srv = normalize_typename(typename, "srv")
            _add(channels, request_channel(service), f"{srv}_Request", "request", project, pub=nname,
                 service=service)
    for nname, _publish, _subscribe, _services, clients in endpoints:
        for service, typename in clients.items():
            srv = normalize_typename(typename, "srv")
            server = channels[request_channel(service)].subscribers[0]
            name = reply_channel(service, nname)
            _add(channels, name, f"{srv}_Response", "reply", project, pub=server, service=service)
            _add(channels, name, f"{srv}_Response", "reply", project, sub=nname, service=service)
    return channels


@dataclass(frozen=True)
class Placement:
    """Where each node of the plan runs, as the transport rule needs it."""

    process_of: dict[str, str]  # node -> its process (a target's, or the launcher's)
    host_of: dict[str, str]  # node -> its host ("" on one machine)
    fpga_of: dict[str, str]  # hardware node -> its fpga target
    gateways: dict[str, str] = field(default_factory=dict)  # gateway node -> its fpga target
    # (gateway, topic): topics an fpga target's hardware takes from ROS 1 itself, not through the bridge
    received_from_ros1: set[tuple[str, str]] = field(default_factory=set)


def edge_transport(channel: str, publisher: str, subscriber: str, placement: Placement) -> TransportKind | None:
    """The one transport of one edge (None: no edge), the cheapest the mapping allows.

    Inside one fpga target: its topic network (``hw``); a hardware node's software peers reach it
    through its gateway, so no edge of theirs touches it; between hosts: DDS; between processes:
    shared memory; within one process: in-process.
    """
    fpga_of = placement.fpga_of
    if publisher == ROS1_BRIDGE and (subscriber, channel) in placement.received_from_ros1:
        return None
    if publisher in fpga_of or subscriber in fpga_of:
        return "hw" if fpga_of.get(publisher) == fpga_of.get(subscriber) else None
    if publisher in placement.gateways and publisher == subscriber:
        return None  # what a gateway publishes came out of the hardware it feeds
    if placement.host_of[publisher] != placement.host_of[subscriber]:
        return "dds"
    return "inproc" if placement.process_of[publisher] == placement.process_of[subscriber] else "shm"


def _target_plan(name: str, target: TargetSpec, host: str, framed: tuple[tuple[str, ...], tuple[str, ...]]
                 ) -> TargetPlan:
    exports, imports = framed
    return TargetPlan(name=name, kind=target.kind, cpus=tuple(target.cpus), clock_mhz=target.clock_mhz or 100.0,
                      data_width=target.data_width, part=target.part or "", host=host, sim=target.sim or "verilator",
                      ros1_export=tuple(exports), ros1_import=tuple(imports),
                      tcpros_frame_bytes=target.tcpros_frame_bytes, stuck_cycles=target.stuck_cycles,
                      board=target.board or "")


def _node_plan(project: LoadedProject, name: str, spec: NodeSpec) -> NodePlan:
    return NodePlan(
        name=name, run=spec.run, target=spec.target, parameters=dict(spec.parameters), restart=spec.restart,
        max_restarts=spec.max_restarts, required=spec.required,
        publish=spec.types("publish") | project.lifecycle_events_heard(name),
        subscribe=spec.types("subscribe"), services=spec.types("services") | project.parameter_services_called(name),
        clients=spec.types("clients"),
        actions={a: normalize_typename(t, "action") for a, t in spec.types("actions").items()},
        action_clients={a: normalize_typename(t, "action") for a, t in spec.types("action_clients").items()},
        max_goals=spec.max_goals(), hw=spec.hw or "", args=tuple(spec.args), namespace=spec.namespace,
        remap=dict(spec.remap), ros_name=spec.name or "", env=dict(spec.env), root=project.node_roots.get(name, ""),
        memory=tuple(spec.memory), lifecycle=spec.lifecycle or "", optional=spec.optional)


def _gateway_plan(channels: dict[str, ChannelPlan], gateway: str, target: str) -> NodePlan:
    return NodePlan(name=gateway, run=SYSTEM_NODES["gateway"], target=target, parameters={"target": target},
                    publish=_endpoints_of(channels, gateway, "publish"),
                    subscribe=_endpoints_of(channels, gateway, "subscribe"),
                    services=_services_of(channels, gateway))


def _clock_followers(project: LoadedProject, process_of: dict[str, str], fpga_of: dict[str, str],
                     speaks_ros1: set[str]) -> dict[str, str]:
    """``use_sim_time``: a clock follower per process that runs nodes, on one of the targets of that process."""
    followers: dict[str, str] = {}
    for node, spec in project.model.nodes.items():
        if node in fpga_of or node in speaks_ros1:
            continue
        name = CLOCK_PREFIX + process_of[node]
        followers.setdefault(name, spec.target)
    return followers


def _add_gateways(channels: dict[str, ChannelPlan], fpga_of: dict[str, str],
                  from_ros1: set[tuple[str, str]]) -> dict[str, str]:
    """Give each fpga target a gateway node on every topic it shares with software; gateway -> target.

    The gateway subscribes where a node off the target publishes to one of its hardware nodes,
    and publishes where one off the target subscribes to them (a hardware node of another fpga
    target counts as off: two targets meet through their gateways). What the ROS 1 bridge imports
    does not count where the target's hardware receives it from ROS 1 itself (``from_ros1``).
    """
    gateways: dict[str, str] = {}
    for channel in list(channels.values()):
        for target in sorted({fpga_of[n] for n in (*channel.publishers, *channel.subscribers) if n in fpga_of}):
            gateway = gateway_node(target)
            into = any(fpga_of.get(n) != target and not (n == ROS1_BRIDGE and (gateway, channel.name) in from_ros1)
                       for n in channel.publishers) and \
                any(fpga_of.get(n) == target for n in channel.subscribers)
            out_of = any(fpga_of.get(n) != target for n in channel.subscribers) and \
                any(fpga_of.get(n) == target for n in channel.publishers)
            if into or out_of:
                gateways[gateway] = target
                _add(channels, channel.name, channel.type, channel.kind, None,  # type: ignore[arg-type]
                     pub=gateway if out_of else None, sub=gateway if into else None, service=channel.service)
    return gateways


def _endpoints_of(channels: dict[str, ChannelPlan], node: str, role: str) -> dict[str, str]:
    return {c.name: c.type for c in channels.values()
            if c.kind == "topic" and node in (c.publishers if role == "publish" else c.subscribers)}


def _services_of(channels: dict[str, ChannelPlan], gateway: str) -> dict[str, str]:
    """The services a gateway serves for its target's hardware servers: name -> srv type."""
    return {c.service: c.type.removesuffix("_Request") for c in channels.values()
            if c.kind == "request" and gateway in c.subscribers}


def _add(channels: dict[str, ChannelPlan], name: str, typename: str, kind: str, project: LoadedProject,
         pub: str | None = None, sub: str | None = None, service: str = "") -> None:
    existing = channels.get(name)
    if existing is None:
        if kind == "topic":
            spec = project.model.topics.get(name)
            # /clock: only the latest time matters, and a simulator must never wait for a reader
            default = QoS(history="keep_last", depth=1) if name == CLOCK_TOPIC else QoS()
            qos = spec if spec is not None else action_topic_qos(name) or default
        else:
            qos = SERVICE_QOS
        existing = ChannelPlan(name, typename, kind, qos, (), (), service,  # type: ignore[arg-type]
                               qos_given=kind != "topic" or name in project.model.topics)
    publishers = existing.publishers + ((pub,) if pub and pub not in existing.publishers else ())
    subscribers = existing.subscribers + ((sub,) if sub and sub not in existing.subscribers else ())
    channels[name] = replace(existing, publishers=publishers, subscribers=subscribers)


def plan_file(path: str | Path, types: TypeRegistry | None = None) -> Plan:
    return plan(load_project(path), types)
