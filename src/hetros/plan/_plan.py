"""The architecture graph the runtime executes: computed once, before anything runs.

The planner (``hetros.project``) produces a :class:`Plan`; the launcher and every
worker process (``hetros.runtime``) read the same plan (as JSON: no pickle crosses a process), so
every process opens exactly the transports the plan names. There is no master
and no discovery: this is ROS-lite's masterless static initialisation.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property
from typing import Any, Literal

from .._errors import InputFileError
from .._files import dataclass_problem, parse_json
from .._qos import QoS
from ._names import join_namespace

# inproc: one process; shm: one host; dds: between hosts; hw: an fpga target's topic network;
# tcpros: every endpoint of a `kind: ros1` node (its peers are the ROS 1 master's, not edges)
TransportKind = Literal["inproc", "shm", "dds", "hw", "tcpros"]
ROS1_TRANSPORT: TransportKind = "tcpros"
# nearest first: an endpoint with edges of several kinds feeds (and drains) the cheapest first
TRANSPORT_ORDER: tuple[str, ...] = ("inproc", "shm", "dds", "hw", "tcpros")
# Both directions of every service, whatever carries them: deep enough for bursts of calls,
# patient enough for a slow handler.
SERVICE_QOS = QoS(depth=64, publish_timeout=30.0)
# The process that runs ``hetros launch``: thread targets live in it.
LAUNCHER = "launcher"
# the nodes (and thread targets) the planner adds when the project shares endpoints with ROS 1 or ROS 2
ROS1_BRIDGE = "hetros_ros1_bridge"
ROS2_BRIDGE = "hetros_ros2_bridge"
# the node the planner adds to each fpga target whose topics cross to software: it runs the target's
# simulator and is the software end of every gateway (see ``gateway_node``)
GATEWAY_PREFIX = "hetros_gateway_"
# with ``use_sim_time``: the node the planner adds to each process to follow /clock for the process' clock
CLOCK_PREFIX = "hetros_clock_"
CLOCK_TOPIC = "/clock"
CLOCK_TYPE = "rosgraph_msgs/msg/Clock"


# What the system nodes the planner adds run: "module:function", resolved by the process that runs
# them (the plan names code, it imports none). tests/unit/test_layers.py resolves every entry.
SYSTEM_NODES: dict[str, str] = {
    "gateway": "hetros.launch.system._gateway:gateway",
    "clock_follower": "hetros.runtime._clock:follow_clock",
    "ros1_bridge": "hetros.launch.system._ros1_bridge:bridge",
    "ros2_bridge": "hetros.launch.system._ros2_bridge:bridge",
}


def gateway_node(target: str) -> str:
    """The gateway node of fpga target ``target``: in the target's own process, it subscribes to what
    software publishes to the target's hardware nodes and publishes what they publish to software."""
    return GATEWAY_PREFIX + target
ChannelKind = Literal["topic", "request", "reply"]


def process_name(target: str, kind: str) -> str:
    """The process a target's nodes run in: threads share the launcher's, the others run alone."""
    return LAUNCHER if kind == "thread" else target


@dataclass(frozen=True)
class TargetPlan:
    name: str
    kind: str
    cpus: tuple[int, ...] = ()
    # fpga targets: the topic network's clock and stream width, and the device
    clock_mhz: float = 100.0
    data_width: int = 64
    part: str = ""
    # the machine (a name in Plan.hosts; "" when the project names no hosts)
    host: str = ""
    # fpga targets under ``hetros launch``: the simulator that runs the hardware
    sim: str = "verilator"
    # fpga targets: topics whose ROS 1 side the hardware frames itself (hardware TCPROS), published to
    # ROS 1 subscribers, or subscribed from ROS 1 publishers; the gateway registers them
    ros1_export: tuple[str, ...] = ()
    ros1_import: tuple[str, ...] = ()
    tcpros_frame_bytes: int = 4096
    # fpga targets: cycles an input may wait on a node that takes no beat before the launch stops
    stuck_cycles: int = 10_000_000
    # fpga targets: the board (zcu104, pynq-z2, ultra96), "" for none: the gateway then goes through the
    # PYNQ-shaped board surface (``hetros.launch.system.board``)
    board: str = ""


@dataclass(frozen=True)
class HostPlan:
    name: str
    address: str
    ssh: str = ""


@dataclass(frozen=True)
class NodePlan:
    name: str
    run: str
    target: str
    parameters: dict[str, Any] = field(default_factory=dict)
    restart: str = "never"
    max_restarts: int = 3
    required: bool = False
    publish: dict[str, str] = field(default_factory=dict)
    subscribe: dict[str, str] = field(default_factory=dict)
    services: dict[str, str] = field(default_factory=dict)
    clients: dict[str, str] = field(default_factory=dict)
    # name -> action type; their services and topics are in the four tables above too
    actions: dict[str, str] = field(default_factory=dict)
    action_clients: dict[str, str] = field(default_factory=dict)
    # action name -> how many of its goals execute at once
    max_goals: dict[str, int] = field(default_factory=dict)
    # "module:Component": the node's hardware implementation, which runs where it is on an fpga target
    hw: str = ""
    # the node's command-line arguments (its sys.argv[1:], a script's or a module:function's)
    args: tuple[str, ...] = ()
    # how its code's names resolve (``plan.resolve_name``): namespace, remaps, its ROS name ("" = its own)
    namespace: str = ""
    remap: dict[str, str] = field(default_factory=dict)
    ros_name: str = ""
    # environment variables its process sets before nodes start
    env: dict[str, str] = field(default_factory=dict)
    # the folder its run: is found in ("" = the project's)
    root: str = ""
    # fpga: the topics its hardware reads and writes in memory through its AXI4 port (``memory:``)
    memory: tuple[str, ...] = ()
    # a managed node: the lifecycle state the launch brings it to ("" = not managed by the project)
    lifecycle: str = ""
    # its failure is reported and ends nothing (``optional:``)
    optional: bool = False


@dataclass(frozen=True)
class ChannelPlan:
    """One topic, or one direction of one service, with its endpoints."""

    name: str
    type: str
    kind: ChannelKind
    qos: QoS
    publishers: tuple[str, ...]
    subscribers: tuple[str, ...]
    service: str = ""
    # the project file sets this topic's QoS (topics:); where it does not, an endpoint's own deadline,
    # which shapes no transport, is the one that endpoint watches (as ROS 2 endpoints each have theirs)
    qos_given: bool = True


@dataclass(frozen=True)
class EdgePlan:
    channel: str
    publisher: str
    subscriber: str
    transport: TransportKind


@dataclass(frozen=True)
class Plan:
    name: str
    root: str
    message_paths: tuple[str, ...]
    targets: dict[str, TargetPlan]
    nodes: dict[str, NodePlan]
    channels: dict[str, ChannelPlan]
    edges: tuple[EdgePlan, ...]
    # the ROS 1 master of `external: ros1:` or `kind: ros1` targets ("" without either): parameters
    # not in the project come from it
    ros1_master: str = ""
    # the interface ROS 1 nodes' slave APIs and TCPROS servers listen on
    ros1_host: str = "127.0.0.1"
    # the QoS of the topics of `kind: ros1` nodes (they are not hetros channels)
    ros1_qos: dict[str, QoS] = field(default_factory=dict)
    # the machines of the graph (empty: one machine); which of them this runtime is on
    hosts: dict[str, HostPlan] = field(default_factory=dict)
    local_host: str = ""
    on_peer_lost: str = "stop"
    dds_domain: int | None = None
    # of the project file and its message definitions: hosts running different ones refuse each other
    project_hash: str = ""
    # interfaces `hetros foxglove` may listen on besides loopback (the project file's foxglove_hosts)
    foxglove_hosts: tuple[str, ...] = ()
    # every process' clock follows /clock (see CLOCK_PREFIX) instead of the wall
    use_sim_time: bool = False
    # ROS 1's parameter server: global parameters by absolute name, which every rospy node reads
    parameters: dict[str, Any] = field(default_factory=dict)
    # folders node modules are imported from after the project file's own (its python_path:), absolute
    python_path: tuple[str, ...] = ()

    def full_name(self, node: str) -> str:
        spec = self.nodes[node]
        return full_node_name(node, spec.namespace, spec.ros_name)

    def parameter_servers(self) -> dict[str, tuple[str, str]]:
        """Every parameter service of the graph: service -> (node, type). Each node whose Python runs has
        them (as every ROS 2 node does); the system nodes the planner adds have none."""
        servers: dict[str, tuple[str, str]] = {}
        for node, spec in self.nodes.items():
            if spec.run not in SYSTEM_NODES.values() and not self.in_hardware(node) and not self.speaks_ros1(node):
                servers.update({s: (node, t) for s, t in parameter_services(self.full_name(node)).items()})
                if spec.lifecycle:  # a managed node's lifecycle services too
                    servers.update({s: (node, t) for s, t in lifecycle_services(self.full_name(node)).items()})
        return servers

    def process_of(self, node: str) -> str:
        """Threads share their host's launcher process (called 'launcher'); others run alone."""
        target = self.targets[self.nodes[node].target]
        return process_name(target.name, target.kind)

    def host_of(self, node: str) -> str:
        return self.targets[self.nodes[node].target].host

    def on_host(self, host: str) -> Plan:
        """This plan as the runtime of ``host`` sees it: its processes are that host's."""
        if host not in self.hosts:
            raise KeyError(host)
        return replace(self, local_host=host)

    def _here(self, node: str) -> bool:
        return not self.hosts or self.host_of(node) == self.local_host

    def in_hardware(self, node: str) -> bool:
        """A node of an fpga target (other than its gateway): its ``hw:`` implementation runs, in the
        target's simulator, and no process runs its Python."""
        spec = self.nodes[node]
        return self.targets[spec.target].kind == "fpga" and node != gateway_node(spec.target)

    def speaks_ros1(self, node: str) -> bool:
        """A node of a ``kind: ros1`` target: all its endpoints are ROS 1's (TCPROS, ROSRPC)."""
        return self.targets[self.nodes[node].target].kind == "ros1"

    @cached_property
    def _edges_by_endpoint(self) -> dict[tuple[str, str, str], list[EdgePlan]]:
        index: dict[tuple[str, str, str], list[EdgePlan]] = {}
        for edge in self.edges:
            index.setdefault((edge.channel, edge.publisher, "publish"), []).append(edge)
            index.setdefault((edge.channel, edge.subscriber, "subscribe"), []).append(edge)
        return index

    def edges_of(self, channel: str, node: str, role: Literal["publish", "subscribe"]) -> list[EdgePlan]:
        """The edges of ``node``'s endpoint on ``channel``: where it publishes to, or reads from."""
        return list(self._edges_by_endpoint.get((channel, node, role), ()))

    def inputs(self, node: str) -> list[tuple[str, str, bool]]:
        """``(channel, type, envelope)`` of everything ``node`` reads: opened before it runs."""
        if self.speaks_ros1(node):
            spec = self.nodes[node]
            return ([(topic, typename, False) for topic, typename in spec.subscribe.items()]
                    + [(request_channel(service), typename, True) for service, typename in spec.services.items()])
        return [(c.name, c.type, c.kind != "topic") for c in self.channels.values() if node in c.subscribers]

    def transports_of(self, nodes: list[str]) -> list[str]:
        """Every kind of transport the endpoints of ``nodes`` use."""
        kinds = {e.transport for e in self.edges if e.publisher in nodes or e.subscriber in nodes}
        if any(self.speaks_ros1(node) for node in nodes):
            kinds.add(ROS1_TRANSPORT)
        return sorted(kinds)

    def nodes_in(self, process: str) -> list[str]:
        """The nodes whose code runs in ``process`` (hardware nodes run in their target's simulator)."""
        return [n for n in self.nodes if self.process_of(n) == process and self._here(n) and not self.in_hardware(n)]

    def env_of(self, process: str) -> dict[str, str]:
        """The environment its nodes ask of ``process`` (the checks refuse nodes that disagree)."""
        env: dict[str, str] = {}
        for node in self.nodes_in(process):
            env.update(self.nodes[node].env)
        return env

    def runs_here(self, node: str) -> bool:
        """Whether a process of this host runs ``node``'s code."""
        return self._here(node) and not self.in_hardware(node)

    def tap_sites(self, channel: str) -> tuple[Literal["publish", "subscribe"], list[str]]:
        """Where this host looks at ``channel`` from outside (``hetros topic echo``): the processes
        that publish it; else, when it comes from outside hetros or from another host, the first
        process that subscribes to it (one, so that nothing is counted twice)."""
        spec = self.channels[channel]
        publishing = sorted({self.process_of(n) for n in spec.publishers if self.runs_here(n)})
        if publishing:
            return "publish", publishing
        return "subscribe", sorted({self.process_of(n) for n in spec.subscribers if self.runs_here(n)})[:1]

    def processes(self) -> list[str]:
        return sorted({self.process_of(n) for n in self.nodes if self._here(n) and not self.in_hardware(n)}
                      - {LAUNCHER})

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=1, sort_keys=True)

    @classmethod
    def from_json(cls, text: str, where: str = "a launch plan") -> Plan:
        """The plan a launcher wrote (``to_json``); anything else (a changed or forged file) is refused
        naming the first field that is wrong, before any of it is used."""
        raw = parse_json(text, where)
        try:
            plan = cls._from_raw(raw)
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise InputFileError(f"{where} is not a plan hetros wrote ({type(exc).__name__}: {exc}); launch "
                                 "the project again") from None
        problem = dataclass_problem(plan, "plan")
        if problem is not None:
            raise InputFileError(f"{where} is not a plan hetros wrote: {problem}; launch the project again")
        return plan

    @classmethod
    def _from_raw(cls, raw: Any) -> Plan:
        return cls(
            name=raw["name"],
            root=raw["root"],
            message_paths=tuple(raw["message_paths"]),
            targets={k: TargetPlan(v["name"], v["kind"], tuple(v["cpus"]), v.get("clock_mhz", 100.0),
                                   v.get("data_width", 64), v.get("part", ""), v.get("host", ""),
                                   v.get("sim", "verilator"), tuple(v.get("ros1_export", ())),
                                   tuple(v.get("ros1_import", ())), v.get("tcpros_frame_bytes", 4096),
                                   v.get("stuck_cycles", 10_000_000), v.get("board", ""))
                     for k, v in raw["targets"].items()},
            nodes={k: NodePlan(**{**v, "args": tuple(v.get("args", ())), "memory": tuple(v.get("memory", ()))})
                   for k, v in raw["nodes"].items()},
            channels={
                k: ChannelPlan(
                    name=v["name"], type=v["type"], kind=v["kind"], qos=QoS(**v["qos"]),
                    publishers=tuple(v["publishers"]), subscribers=tuple(v["subscribers"]),
                    service=v["service"], qos_given=v.get("qos_given", True),
                )
                for k, v in raw["channels"].items()
            },
            edges=tuple(EdgePlan(**e) for e in raw["edges"]),
            ros1_master=raw.get("ros1_master", ""),
            ros1_host=raw.get("ros1_host", "127.0.0.1"),
            ros1_qos={k: QoS(**v) for k, v in raw.get("ros1_qos", {}).items()},
            hosts={k: HostPlan(**v) for k, v in raw.get("hosts", {}).items()},
            local_host=raw.get("local_host", ""),
            on_peer_lost=raw.get("on_peer_lost", "stop"),
            use_sim_time=raw.get("use_sim_time", False),
            parameters=dict(raw.get("parameters", {})),
            dds_domain=raw.get("dds_domain"),
            project_hash=raw.get("project_hash", ""),
            foxglove_hosts=tuple(raw.get("foxglove_hosts", ())),
            python_path=tuple(raw.get("python_path", ())),
        )


_REQUEST = "/_request"
_REPLY = "/_reply/"


def request_channel(service: str) -> str:
    return f"{service}{_REQUEST}"


def reply_channel(service: str, client: str) -> str:
    return f"{service}{_REPLY}{client}"


ACTION_PREFIX = "/_action/"
# ROS 2's action QoS: feedback reliable and ordered (here keep_all, deep enough for bursts);
# status latched, one array holding every goal's state, so a late client sees the current one
ACTION_TOPIC_QOS = {"feedback": QoS(depth=100), "status": QoS.latched(1)}


def action_endpoints(action: str, typename: str) -> tuple[dict[str, str], dict[str, str]]:
    """An action's three services and two topics, named as ROS 2 names them.

    ``(services, topics)``, each name -> type; the server serves and publishes them, the
    client calls and subscribes. Everything below the node API sees only services and
    topics, so every transport carries actions without knowing them.
    """
    base = action.rstrip("/") + ACTION_PREFIX
    services = {f"{base}send_goal": f"{typename}_SendGoal", f"{base}cancel_goal": "action_msgs/srv/CancelGoal",
                f"{base}get_result": f"{typename}_GetResult"}
    topics = {f"{base}feedback": f"{typename}_FeedbackMessage", f"{base}status": "action_msgs/msg/GoalStatusArray"}
    return services, topics


def action_topic_qos(topic: str) -> QoS | None:
    """The default QoS of an action's feedback or status topic (None for any other topic)."""
    _, sep, part = topic.rpartition(ACTION_PREFIX)
    return ACTION_TOPIC_QOS.get(part) if sep else None


# the services through which ROS 2 tools and parameter clients read and set a node's parameters, each
# under the node's full name (``/ns/talker/get_parameters``)
PARAMETER_SERVICES = {"describe_parameters": "rcl_interfaces/srv/DescribeParameters",
                      "get_parameter_types": "rcl_interfaces/srv/GetParameterTypes",
                      "get_parameters": "rcl_interfaces/srv/GetParameters",
                      "list_parameters": "rcl_interfaces/srv/ListParameters",
                      "set_parameters": "rcl_interfaces/srv/SetParameters",
                      "set_parameters_atomically": "rcl_interfaces/srv/SetParametersAtomically"}


# the services and the topic through which ``ros2 lifecycle``, launch and other nodes drive a managed node,
# each under its full name (``/lc_talker/change_state``)
LIFECYCLE_SERVICES = {"change_state": "lifecycle_msgs/srv/ChangeState",
                      "get_state": "lifecycle_msgs/srv/GetState",
                      "get_available_states": "lifecycle_msgs/srv/GetAvailableStates",
                      "get_available_transitions": "lifecycle_msgs/srv/GetAvailableTransitions",
                      "get_transition_graph": "lifecycle_msgs/srv/GetAvailableTransitions"}
LIFECYCLE_EVENTS = ("transition_event", "lifecycle_msgs/msg/TransitionEvent")
# the transitions one asks of a managed node (lifecycle_msgs/Transition ids): id -> (label, the primary state
# it starts from, the one it ends in when its callback succeeds)
LIFECYCLE_TRANSITIONS = {1: ("configure", "unconfigured", "inactive"), 2: ("cleanup", "inactive", "unconfigured"),
                         3: ("activate", "inactive", "active"), 4: ("deactivate", "active", "inactive"),
                         5: ("shutdown", "unconfigured", "finalized"), 6: ("shutdown", "inactive", "finalized"),
                         7: ("shutdown", "active", "finalized")}


def lifecycle_services(full_name: str) -> dict[str, str]:
    """The lifecycle services of the managed node called ``full_name``: service -> type."""
    return {f"{full_name}/{service}": typename for service, typename in LIFECYCLE_SERVICES.items()}


def full_node_name(key: str, namespace: str = "", ros_name: str = "") -> str:
    """A node's full ROS name (``/r2/talker``): its namespace, then its ROS name (else its key)."""
    return join_namespace(namespace, ros_name or key) or f"/{key}"


def parameter_services(full_name: str) -> dict[str, str]:
    """The parameter services of the node called ``full_name``: service -> type."""
    return {f"{full_name}/{service}": typename for service, typename in PARAMETER_SERVICES.items()}


def service_of(channel: str) -> tuple[str, str]:
    """``(service, client)`` of a reply channel, ``(service, "")`` of a request channel."""
    if channel.endswith(_REQUEST):
        return channel.removesuffix(_REQUEST), ""
    service, _, client = channel.partition(_REPLY)
    return service, client
