"""The project file: one YAML document, validated by pydantic, errors with YAML paths."""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from functools import cached_property
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, field_validator

from .._errors import MessageError, ProjectError
from .._files import read_bytes
from .._qos import QoS
from ..msg import normalize_typename
from ..plan import (
    ACTION_PREFIX,
    LAUNCHER,
    LIFECYCLE_EVENTS,
    action_endpoints,
    full_node_name,
    lifecycle_services,
    parameter_services,
)
from ._expand import declared_args, expand, substitute
from ._names import plain_name_problem

# goals an action server executes at once unless the project file says otherwise
DEFAULT_MAX_GOALS = 8


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class HostSpec(_Strict):
    """A machine of the graph: where its targets run and where its peers find it."""

    address: str = Field(description="the machine's IP address or host name; its peers reach it there, and "
                         "`hetros launch` runs the host whose address is local")
    ssh: str | None = Field(default=None, description="the user `hetros deploy` logs in as over ssh (absent: deploy "
                            "starts this host only when it is the machine deploy runs on)")

    @field_validator("address")
    @classmethod
    def _address(cls, value: str) -> str:
        if not value or any(c.isspace() for c in value) or "/" in value:
            raise ValueError(f"address must be an IP address or host name like '10.0.0.2', not {value!r}")
        return value


_SIMULATORS = ("verilator", "amaranth")


def _simulator(value: str | None) -> str | None:
    if value is not None and value not in _SIMULATORS:
        hint = (" (Icarus replays the exported Verilog in `hetros hw report`; a launch needs a simulator the gateway "
                "drives a cycle at a time)" if value == "icarus" else "")
        raise ValueError(f"sim must be one of {', '.join(map(repr, _SIMULATORS))}, not {value!r}{hint}")
    return value


class TargetSpec(_Strict):
    kind: Literal["thread", "process", "ros1", "fpga"] = Field(
        description="thread: in the launcher's process; process: a process of its own; ros1: a process whose "
                    "nodes are ROS 1 nodes (TCPROS, ROSRPC); fpga: an FPGA whose topics become an AXI-Stream network")
    cpus: list[int] = Field(default_factory=list, description="the CPUs the target's process is pinned to "
                            "(empty: any)")
    clock_mhz: float | None = Field(default=None, gt=0, description="fpga: the clock of the generated topic "
                                    "network (absent: 100 MHz)")
    data_width: int = Field(default=64, ge=8, le=1024, multiple_of=8, description="fpga: the stream width in bits")
    part: str | None = Field(default=None, description="fpga: the device, for reports")
    sim: Annotated[str | None, AfterValidator(_simulator)] = Field(
        default=None, description="fpga: the simulator `hetros launch` runs the target's hardware in (absent: "
        "verilator, Debian's, compiled once per design, millions of cycles a second; amaranth: Amaranth's own, "
        "no compiler, thousands of cycles a second, for small designs)")
    host: str | None = Field(default=None, description="the machine it runs on, a name under hosts: (absent: the "
                             "first host, or this machine without hosts:)")
    tcpros_frame_bytes: int = Field(default=4096, ge=16, le=1 << 26, description="fpga: the ROS 1 bytes its "
                                    "hardware TCPROS framer holds for a type of variable size: those before the "
                                    "type's last string or sequence (the rest streams); a message whose held part "
                                    "is longer is refused loudly")
    stuck_cycles: int = Field(default=10_000_000, ge=1000, le=1 << 40, description="fpga: cycles a hardware node "
                              "may hold a waiting input message without taking a beat before the launch stops, "
                              "naming it (a node that never raises TREADY)")
    board: Literal["zcu104", "pynq-z2", "ultra96"] | None = Field(
        default=None, description="fpga: the board; `hetros launch` then drives the target through the board "
        "gateway (PYNQ's Overlay, allocate and DMA channels; `pip install hetros[board]` on the board, the "
        "simulator behind the same surface elsewhere), and `hetros hw export` defaults to it")

    @field_validator("cpus")
    @classmethod
    def _cpus(cls, value: list[int]) -> list[int]:
        for cpu in value:
            if cpu < 0:
                raise ValueError(f"cpu numbers must be >= 0, not {cpu!r}")
        return value


class EndpointSpec(_Strict):
    """An endpoint with its own QoS request, checked against its peers' (ROS 2 request/offer)."""

    type: str = Field(description="the message type, as pkg/msg/Type")
    reliability: Literal["reliable", "best_effort"] | None = Field(
        default=None, description="requested (a subscriber) or offered (a publisher); absent: the topic's")
    durability: Literal["volatile", "transient_local"] | None = Field(
        default=None, description="requested or offered; absent: the topic's")
    deadline: float | None = Field(default=None, gt=0, description="seconds, requested or offered; absent: the "
                                   "topic's")
    liveliness: Literal["automatic", "manual_by_topic"] | None = Field(
        default=None, description="requested or offered; absent: the topic's")
    lease_duration: float | None = Field(default=None, gt=0, description="seconds, requested or offered; absent: "
                                         "the topic's")


class ActionSpec(_Strict):
    """An action server with a bound on the goals it executes at once (the rest wait, accepted)."""

    type: str = Field(description="the action type, as pkg/action/Type")
    max_goals: int = Field(default=DEFAULT_MAX_GOALS, ge=1, le=1024,
                           description="how many goals execute at once; later ones wait, accepted")


class NodeSpec(_Strict):
    run: str = Field(description="module:function (or module:Class) of the node's code, the module beside the "
                     "project file; or the path of a script (relative to the project file) run as __main__, "
                     "as a ROS 1 node's script is")
    args: list[str] = Field(default_factory=list, description="the node's command-line arguments (its sys.argv[1:], "
                                                          "for a script or a module:function alike)")
    hw: str | None = Field(default=None, description="module:Component or file.v:module: the node's hardware "
                           "implementation, an Amaranth component or a Verilog module whose stream ports are named "
                           "after its topics; on an fpga target it is what runs")
    memory: list[str] = Field(default_factory=list, description="fpga: the topics whose messages the hardware reads "
                              "(a subscribed one) and writes (a published one) in memory, by address, through its "
                              "AXI4 port `mem`, instead of receiving them as a stream: one of each, of one type; the "
                              "stream ports then carry descriptors and completions (docs/GUIDE.md, Memory-mapped "
                              "messages)")
    target: str = Field(default="main", description="the target it runs on, a name under targets: (absent: main, "
                        "the default thread target)")
    publish: dict[str, str | EndpointSpec] = Field(
        default_factory=dict, description="topic -> type, or topic -> {type: ..., QoS offered}")
    subscribe: dict[str, str | EndpointSpec] = Field(
        default_factory=dict, description="topic -> type, or topic -> {type: ..., QoS requested}")
    services: dict[str, str] = Field(default_factory=dict, description="service served -> pkg/srv/Type")
    clients: dict[str, str] = Field(default_factory=dict, description="service called -> pkg/srv/Type")
    actions: dict[str, str | ActionSpec] = Field(
        default_factory=dict, description="action served -> pkg/action/Type, or -> {type: ..., max_goals: N}")
    action_clients: dict[str, str] = Field(default_factory=dict, description="action called -> pkg/action/Type")
    parameters: dict[str, Any] = Field(default_factory=dict, description="name -> value, read by "
                                       "node.get_parameter(name)")
    restart: Literal["never", "on-failure"] = Field(default="never", description="on-failure: a node that raised "
                                                   "starts again, its subscriptions kept")
    required: bool = Field(default=False, description="when this node returns, the whole launch ends")
    optional: bool = Field(default=False, description="a node whose failure (it raised, or a thread of it did) "
                           "is reported but ends nothing: the graph goes on, and the launch's exit code is not "
                           "non-zero for it")
    lifecycle: Literal["unconfigured", "inactive", "active"] | None = Field(
        default=None, description="a managed node (rclpy.lifecycle): the state the launch brings it to before the "
        "graph runs, as launch_ros's transitions do (absent: it stays where its code puts it)")
    max_restarts: int = Field(default=3, ge=0, description="restarts after which a failing node stays failed")
    namespace: str = Field(default="", description="the node's namespace: relative endpoint names (chatter, "
                           "~/x) resolve under it, as in ROS; a relative namespace nests in its group's or "
                           "include's")
    name: str | None = Field(default=None, description="the node's ROS name (rclpy's get_name(), logs, ROS "
                             "graphs); absent: the name its code gives, else the key")
    remap: dict[str, str] = Field(default_factory=dict, description="name -> name: topics, services and actions "
                                  "renamed after resolution (relative names resolve under the namespace)")
    env: dict[str, str] = Field(default_factory=dict, description="environment variables of the node's process "
                                "(nodes sharing a process must agree)")
    parameter_files: list[str] = Field(default_factory=list, description="ROS 2 parameter files (node: "
                                       "{ros__parameters: ...}, /** wildcards), relative to the project file; "
                                       "parameters: wins over them")
    instances: dict[str, InstanceSpec] = Field(default_factory=dict, description="name -> an instance: the node "
                                               "runs once per entry (not under its own key), each with its own "
                                               "namespace, name, remaps, parameters")

    def types(self, section: str) -> dict[str, str]:
        """Endpoint name -> type name for a section, its actions' services and topics included.

        An action server serves three services and publishes two topics, a client the other
        way round (``action_endpoints``): from here on they are plain endpoints.
        """
        table: dict[str, str | EndpointSpec | ActionSpec] = getattr(self, section)
        out = {k: (v if isinstance(v, str) else v.type) for k, v in table.items()}
        if section in _DERIVED:
            actions, part = _DERIVED[section]
            for action, typename in self.types(actions).items():
                try:
                    full = normalize_typename(typename, "action")
                except MessageError:
                    continue  # `hetros check` reports the action's type, once
                out.update(action_endpoints(action, full)[part])
        return out

    def action_of(self, section: str, endpoint: str) -> tuple[str, str] | None:
        """``(actions section, action)`` when ``endpoint`` of ``section`` belongs to an action."""
        actions, _part = _DERIVED.get(section, ("", 0))
        for action in getattr(self, actions, {}):
            if endpoint.startswith(action.rstrip("/") + ACTION_PREFIX):
                return actions, action
        return None

    def max_goals(self) -> dict[str, int]:
        return {k: DEFAULT_MAX_GOALS if isinstance(v, str) else v.max_goals for k, v in self.actions.items()}

    def endpoint(self, section: str, name: str) -> EndpointSpec | None:
        value = getattr(self, section).get(name)
        return value if isinstance(value, EndpointSpec) else None

    @field_validator("run")
    @classmethod
    def _run(cls, value: str) -> str:
        module, sep, attr = value.partition(":")
        if sep and (not module or not attr):
            raise ValueError(f"run must be 'module:function_or_class' or a script's path, not {value!r}")
        if not value.strip():
            raise ValueError("run must not be empty: give 'module:function_or_class' or a script's path")
        return value

    @field_validator("hw")
    @classmethod
    def _hw(cls, value: str | None) -> str | None:
        module, sep, attr = (value or "").partition(":")
        if value is not None and (not sep or not module or not attr):
            raise ValueError(f"hw must be 'module:Component' (Amaranth) or 'file.v:module' (Verilog), not {value!r}")
        return value


class InstanceSpec(_Strict):
    """One instance of a node: what differs from the node's own entry."""

    namespace: str | None = Field(default=None, description="its namespace (absent: the node's)")
    name: str | None = Field(default=None, description="its ROS name (absent: the node's)")
    target: str | None = Field(default=None, description="its target (absent: the node's)")
    remap: dict[str, str] = Field(default_factory=dict, description="remaps added to the node's")
    parameters: dict[str, Any] = Field(default_factory=dict, description="parameters over the node's")
    parameter_files: list[str] = Field(default_factory=list, description="parameter files after the node's")
    env: dict[str, str] = Field(default_factory=dict, description="environment over the node's")
    args: list[str] | None = Field(default=None, description="the node's arguments (absent: the node's)")


class GroupSpec(_Strict):
    """Nodes that share a namespace, remaps, environment and parameters (ROS launch's group)."""

    namespace: str = Field(default="", description="the namespace of the group's nodes (a node's relative "
                           "namespace nests in it)")
    remap: dict[str, str] = Field(default_factory=dict, description="remaps of every node in the group")
    env: dict[str, str] = Field(default_factory=dict, description="environment of every node in the group")
    parameters: dict[str, Any] = Field(default_factory=dict, description="parameters of every node in the group")
    parameter_files: list[str] = Field(default_factory=list, description="parameter files of every node in "
                                       "the group")
    nodes: dict[str, NodeSpec] = Field(description="name -> a node, as under the project's nodes:")


class IncludeSpec(_Strict):
    """Another project file's nodes, targets and topics, under a namespace."""

    file: str = Field(description="the project file, relative to this one")
    namespace: str = Field(default="", description="the namespace its nodes' relative names resolve under")
    args: dict[str, str | int | float | bool] = Field(default_factory=dict, description="values for its "
                                                      "$(arg name) substitutions")
    targets: dict[str, str] = Field(default_factory=dict, description="its target -> a target of this file; "
                                    "targets not named here stay its own, named <include>_<target>")


NodeSpec.model_rebuild()


# which actions' endpoints each section holds: (actions section, 0 = services / 1 = topics)
_DERIVED = {"services": ("actions", 0), "publish": ("actions", 1),
            "clients": ("action_clients", 0), "subscribe": ("action_clients", 1)}


class Bridged(_Strict):
    """What a bridge carries across: hetros endpoints exported, the other graph's imported."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)
    export: list[str] = Field(default_factory=list, description="topics hetros publishes, offered to the other "
                              "graph's subscribers")
    import_: list[str] = Field(default_factory=list, alias="import", description="topics the other graph "
                               "publishes, delivered to hetros subscribers")
    export_services: list[str] = Field(default_factory=list, description="hetros services the other graph's "
                                       "clients may call")
    import_services: list[str] = Field(default_factory=list, description="the other graph's services hetros "
                                       "clients may call")
    export_actions: list[str] = Field(default_factory=list, description="hetros action servers offered to the "
                                      "other graph's clients")
    import_actions: list[str] = Field(default_factory=list, description="the other graph's action servers, for "
                                      "hetros action clients")

    def listed(self) -> dict[str, list[str]]:
        """The six lists by their YAML keys (``export``, ``import``, ``export_services``, ...)."""
        return {"export": list(self.export), "import": list(self.import_),
                "export_services": list(self.export_services), "import_services": list(self.import_services),
                "export_actions": list(self.export_actions), "import_actions": list(self.import_actions)}


class Ros1Spec(Bridged):
    """Topics shared with a ROS 1 graph through its master (``hetros master`` or roscore)."""

    master: str | None = Field(default=None, description="the ROS 1 master's URI (absent: $ROS_MASTER_URI, else "
                               "http://127.0.0.1:11311/)")
    host: str = Field(default="127.0.0.1", description="the interface the bridge's slave API and TCPROS server "
                      "listen on")

    @field_validator("master")
    @classmethod
    def _master(cls, value: str | None) -> str | None:
        if value is not None and not (value.startswith("http://") and value.rstrip("/").rsplit(":", 1)[-1].isdigit()):
            raise ValueError(f"master must be a URI like 'http://127.0.0.1:11311/', not {value!r}")
        return value


class Ros2Spec(Bridged):
    """Topics, services and actions shared with a ROS 2 graph over DDS (rmw_cyclonedds's wire)."""

    domain: int | None = Field(default=None, ge=0, le=232, description="the ROS 2 domain id (absent: "
                               "$ROS_DOMAIN_ID, else 0)")
    interface: str = Field(default="127.0.0.1", description="the one interface the DDS participant uses "
                           "($CYCLONEDDS_URI replaces interface, peers and multicast)")
    peers: list[str] = Field(default_factory=lambda: ["127.0.0.1"], description="where static discovery looks "
                             "for ROS 2 participants")
    multicast: bool = Field(default=False, description="whether discovery also uses multicast")


class ExternalSpec(_Strict):
    ros2: Ros2Spec | None = Field(default=None, description="share topics, services and actions with a ROS 2 "
                                  "graph over DDS")
    ros1: Ros1Spec | None = Field(default=None, description="share topics, services and actions with a ROS 1 "
                                  "graph through its master")


_UNITS = {"": 1, "B": 1, "KIB": 1 << 10, "MIB": 1 << 20, "GIB": 1 << 30, "TIB": 1 << 40,
          "KB": 10**3, "MB": 10**6, "GB": 10**9}


def parse_size(value: int | str) -> int:
    """Bytes from ``1073741824``, ``"1GiB"`` or ``"512 MiB"``."""
    if isinstance(value, int) and not isinstance(value, bool):
        if value <= 0:
            raise ValueError(f"a size must be positive bytes, not {value!r}")
        return value
    text = str(value).strip()
    number = text.rstrip("KMGTiBb ").strip()
    unit = text[len(number):].strip().upper()
    if not number.isdigit() or unit not in _UNITS or int(number) == 0:
        raise ValueError(f"a size must be bytes or a number with KiB/MiB/GiB (like '1GiB'), not {value!r}")
    return int(number) * _UNITS[unit]


def _unknown_key(loc: list[str]) -> str:
    """An unknown key's error: the nearest known key when one is close, else every key there."""
    from ._reference import known_keys

    known = known_keys(tuple(loc[:-1]))
    near = difflib.get_close_matches(loc[-1], known, n=1, cutoff=0.6)
    if near:
        return f"unknown key {loc[-1]!r}; did you mean {near[0]!r}?"
    listed = f": one of {', '.join(known)}" if known else ""
    return f"unknown key {loc[-1]!r}{listed} (docs/PROJECT_FILE.md lists every key)"


def _plain_names(what: str, names: Iterable[str]) -> None:
    for name in names:
        if problem := plain_name_problem(what, name):
            raise ValueError(problem)


class ChainSpec(_Strict):
    first: str = Field(description="the topic the chain starts at: a message's publish there starts its clock")
    last: str = Field(description="the topic it ends at: the publish there of what became of the message stops it")
    deadline_ms: float | None = Field(default=None, gt=0, description="what its latency's median must stay within "
                                      "(`hetros advise` looks for a mapping that meets it)")


class Project(_Strict):
    name: str = Field(description="the project's name: an ASCII letter, then letters, digits, _ or -")
    messages: list[str] = Field(default_factory=list, description="folders of .msg/.srv/.action packages, "
                                "relative to the project file")
    python_path: list[str] = Field(default_factory=list, description="folders, relative to the project file, "
                                   "where the nodes' modules are imported from besides the project file's own "
                                   "(a ROS package's source, say, when the project file lives elsewhere)")
    shm_budget: int | str = Field(default="1GiB", description="the most shared memory all topics may reserve "
                                  "(bytes, or like 4GiB)")
    targets: dict[str, TargetSpec] = Field(default_factory=lambda: {"main": TargetSpec(kind="thread")},
                                           description="name -> where nodes run (absent: one thread target, main)")
    nodes: dict[str, NodeSpec] = Field(default_factory=dict, description="name -> a node: its code, its target, "
                                       "its endpoints (a project may also bring its nodes by groups: and include:)")
    topics: dict[str, QoS] = Field(default_factory=dict, description="topic -> its QoS (absent: reliable, keep_all, "
                                   "depth 10)")
    external: ExternalSpec | None = Field(default=None, description="the ROS 1 and ROS 2 graphs this one joins")
    hosts: dict[str, HostSpec] = Field(default_factory=dict, description="name -> a machine the graph spans; "
                                       "edges between them go over DDS")
    on_peer_lost: Literal["stop", "continue"] = Field(default="stop", description="when a host goes away: stop "
                                                      "the whole graph, or keep the rest running until it returns")
    dds_domain: int | None = Field(default=None, ge=0, le=232, description="the DDS domain of the edges between "
                                   "hosts (absent: $ROS_DOMAIN_ID, else 0)")
    args: dict[str, str | int | float | bool] = Field(default_factory=dict, description="name -> default: the "
                                                      "values of $(arg name) in this file (an include's args: "
                                                      "override them); $(env NAME) and $(env NAME default) "
                                                      "read the environment")
    groups: dict[str, GroupSpec] = Field(default_factory=dict, description="name -> nodes sharing a namespace, "
                                         "remaps, environment and parameters")
    include: dict[str, IncludeSpec] = Field(default_factory=dict, description="name -> another project file "
                                            "whose nodes join this graph (named <name>_<node>) under a "
                                            "namespace")
    foxglove_hosts: list[str] = Field(default_factory=list, description="interfaces `hetros foxglove` may listen "
                                      "on besides 127.0.0.1 (its protocol has no authentication: whoever reaches "
                                      "the port sees every topic)")
    parameters: dict[str, Any] = Field(default_factory=dict, description="ROS 1's parameter server: absolute "
                                       "name (/robot/speed) -> value, read by every rospy node by its full or "
                                       "relative name (a node's private ones are under nodes.<node>.parameters)")
    use_sim_time: bool = Field(default=False, description="every node's clock (get_clock, create_timer, rate) "
                               "follows /clock (rosgraph_msgs/msg/Clock, published by a simulator node or "
                               "`hetros play --clock`) instead of the wall")
    chains: dict[str, ChainSpec] = Field(default_factory=dict, description="name -> a path of topics whose "
                                         "latency matters (first topic to last): `hetros advise` predicts, "
                                         "meets and verifies it")

    @field_validator("parameters")
    @classmethod
    def _global_names(cls, value: dict[str, Any]) -> dict[str, Any]:
        for name in value:
            if not name.startswith("/") or "//" in name or (name.endswith("/") and name != "/"):
                raise ValueError(f"a global parameter's name must be absolute (/robot/speed), not {name!r}")
        return value

    @field_validator("shm_budget")
    @classmethod
    def _budget(cls, value: int | str) -> int | str:
        parse_size(value)
        return value

    @property
    def shm_budget_bytes(self) -> int:
        return parse_size(self.shm_budget)

    @field_validator("name")
    @classmethod
    def _name(cls, value: str) -> str:
        _plain_names("a project", [value])
        return value

    @field_validator("targets")
    @classmethod
    def _targets(cls, value: dict[str, TargetSpec]) -> dict[str, TargetSpec]:
        if LAUNCHER in value:
            raise ValueError(f"{LAUNCHER!r} is reserved for the launching process; pick another name")
        _plain_names("a target", value)
        return value

    @field_validator("hosts")
    @classmethod
    def _hosts(cls, value: dict[str, HostSpec]) -> dict[str, HostSpec]:
        _plain_names("a host", value)
        return value


class LoadedProject:
    """A validated project plus where it came from (for paths and line numbers)."""

    def __init__(self, model: Project, path: Path, lines: dict[tuple[str, ...], int],
                 aliases: dict[tuple[str, ...], tuple[str, ...]] | None = None,
                 roots: dict[str, str] | None = None) -> None:
        self.model = model
        self.path = path
        self.root = path.parent
        self._lines = lines
        # a node's or endpoint's expanded path -> the path it was written at (groups, instances, includes)
        self._aliases = aliases or {}
        # node -> the folder its run: is found in, for nodes of an included file elsewhere
        self.node_roots = roots or {}
        # where node modules are imported from: the project file's folder, then its python_path:
        self.import_folders = (self.root.resolve(), *((self.root / p).resolve() for p in model.python_path))
        # topics a recording feeds (``hetros play --launch``): subscribing to them needs no publisher
        self.replayed: frozenset[str] = frozenset()

    @cached_property
    def _parameter_services_called(self) -> dict[str, dict[str, str]]:
        called = {service for spec in self.model.nodes.values() for service in spec.clients}
        found: dict[str, dict[str, str]] = {}
        for key, spec in self.model.nodes.items():
            target = self.model.targets.get(spec.target)
            if target is not None and target.kind in ("fpga", "ros1"):
                continue
            full = full_node_name(key, spec.namespace, spec.name or "")
            offered = parameter_services(full) | (lifecycle_services(full) if spec.lifecycle is not None else {})
            for service, typename in offered.items():
                if service in called:
                    found.setdefault(key, {})[service] = typename
        return found

    def parameter_services_called(self, node: str) -> dict[str, str]:
        """The parameter services of ``node`` (and a managed node's lifecycle services) some node of the
        project calls (an rclpy ``AsyncParameterClient``, a lifecycle manager): the node serves them on the
        graph's transports. Every node answers the command line's requests whatever the project says."""
        return dict(self._parameter_services_called.get(node, {}))

    def lifecycle_events_heard(self, node: str) -> dict[str, str]:
        """A managed node's ``transition_event`` topic when some node of the project subscribes to it: the
        node publishes it on the graph's transports."""
        spec = self.model.nodes[node]
        if spec.lifecycle is None:
            return {}
        topic = f"{full_node_name(node, spec.namespace, spec.name or '')}/{LIFECYCLE_EVENTS[0]}"
        heard = any(topic in other.subscribe for other in self.model.nodes.values())
        return {topic: LIFECYCLE_EVENTS[1]} if heard and topic not in spec.publish else {}

    def where(self, *yaml_path: str | int) -> str:
        """``file:line: a.b.c`` for a YAML path (the line of the nearest known ancestor)."""
        key = tuple(str(p) for p in yaml_path)
        for length in range(len(key), 0, -1):
            if key[:length] in self._aliases:
                key = self._aliases[key[:length]] + key[length:]
                break
        while key and key not in self._lines:
            key = key[:-1]
        line = self._lines.get(key)
        dotted = ".".join(str(p) for p in yaml_path)
        return f"{self.path}:{line}: {dotted}" if line else f"{self.path}: {dotted}"


_SPECS = {"EndpointSpec", "ActionSpec"}
_UNION_TAGS = _SPECS | {"str"}


# A project file lists nodes and topics; one whose aliases expand past this many YAML nodes
# is an alias bomb, not a project.
MAX_EXPANDED_NODES = 1_000_000
MAX_NESTING = 100
_Loader: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _line_index(root: yaml.Node, path: Path) -> dict[tuple[str, ...], int]:
    """YAML path -> line, for error messages; refuses duplicate keys, deep nesting and alias bombs.

    Walks each distinct node once (aliases share nodes), so an alias bomb costs its size in
    the file, not its expansion.
    """
    out: dict[tuple[str, ...], int] = {}
    expanded: dict[int, int] = {}
    stack: list[tuple[yaml.Node, tuple[str, ...]]] = [(root, ())]
    order: list[yaml.Node] = []
    while stack:
        node, prefix = stack.pop()
        if len(prefix) > MAX_NESTING:
            raise ProjectError(f"{path}:{node.start_mark.line + 1}: nested more than {MAX_NESTING} levels "
                               "deep; a project file needs a handful")
        out.setdefault(prefix, node.start_mark.line + 1)
        if id(node) in expanded:
            continue
        expanded[id(node)] = -1
        order.append(node)
        if isinstance(node, yaml.MappingNode):
            keys: dict[str, int] = {}
            for key, value in node.value:
                name = str(key.value)
                line = key.start_mark.line + 1
                if name in keys and name != "<<":
                    raise ProjectError(f"{path}:{line}: {'.'.join((*prefix, name))}: duplicate key {name!r} "
                                       f"(first at line {keys[name]}); YAML keeps only the last, so "
                                       "rename or merge the two")
                keys[name] = line
                child = (*prefix, name)
                out[child] = line
                stack.append((value, child))
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                stack.append((item, (*prefix, str(i))))
    for node in reversed(order):
        children: list[yaml.Node] = []
        if isinstance(node, yaml.MappingNode):
            children = [n for pair in node.value for n in pair]
        elif isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        size = 1 + sum(max(expanded.get(id(c), 1), 1) for c in children)
        if size > MAX_EXPANDED_NODES:
            raise ProjectError(f"{path}:{node.start_mark.line + 1}: its aliases (*name) expand to more than "
                               f"{MAX_EXPANDED_NODES:,} YAML nodes; a project file needs no such "
                               "repetition: write the values out or shorten the chain of aliases")
        expanded[id(node)] = size
    return out


# a project file with its includes is kilobytes; a generated one with thousands of nodes a few MB
PROJECT_LIMIT = 16 << 20


def _read_text(path: Path) -> str:
    raw = read_bytes(path, "project file", limit=PROJECT_LIMIT, error=ProjectError)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise ProjectError(f"{path}:{line}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}); "
                           "save the project file as UTF-8") from None


def load_project(path: str | Path) -> LoadedProject:
    """Read and validate a project file; every error names file:line and the YAML path. Groups, instances,
    includes, namespaces, remaps and parameter files are expanded (``_expand``): the project returned is
    flat, every endpoint under its final name."""
    path = Path(path)
    model, lines = _parse(path, {})

    def load_included(file: Path, args: dict[str, object], depth: int) -> dict[str, Any]:
        return _parse(file, args)[0].model_dump(by_alias=True)
    expanded = expand(model.model_dump(by_alias=True), path, load_included)
    flat = {**model.model_dump(by_alias=True, exclude_unset=True), "nodes": expanded.nodes,
            "targets": expanded.targets, "topics": expanded.topics, "messages": expanded.messages,
            "parameters": expanded.parameters,
            "python_path": expanded.python_path, "groups": {}, "include": {}}
    if not expanded.nodes:
        raise ProjectError(f"{path}:1: the project has no nodes; list them under nodes: (or bring them with "
                           "groups: or include:)")
    try:
        model = Project.model_validate(flat)
    except ValidationError as exc:
        raise ProjectError(f"{path}: after expanding groups, instances and includes: {exc}") from None
    return LoadedProject(model, path, lines, expanded.aliases, expanded.roots)


def _parse(path: Path, args: dict[str, object]) -> tuple[Project, dict[tuple[str, ...], int]]:
    text = _read_text(path)
    if "$(" in text:
        text = substitute(text, path, {**declared_args(text), **args})
    if "\x00" in text:
        raise ProjectError(f"{path}:{text.count(chr(10), 0, text.index(chr(0))) + 1}: a NUL character; "
                           "a project file is YAML text")
    try:
        loader = _Loader(text)
        try:
            tree = loader.get_single_node()
            lines = _line_index(tree, path) if tree is not None else {}
            data = loader.construct_document(tree) if tree is not None else None
        finally:
            loader.dispose()
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        raise ProjectError(f"{path}:{line}: character {exc.character!r} at offset {exc.position} is not "
                           "allowed in YAML; remove it") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else f"{path}:1"
        raise ProjectError(f"{where}: not valid YAML: {getattr(exc, 'problem', None) or exc}") from None
    except RecursionError:
        raise ProjectError(f"{path}:1: nested too deeply to read; a project file needs a handful of levels") from None
    if not isinstance(data, dict):
        raise ProjectError(f"{path}:1: the project file must be a mapping with name, targets and nodes, "
                           f"not {type(data).__name__}")
    try:
        model = Project.model_validate(data)
    except ValidationError as exc:
        loaded = LoadedProject(Project.model_construct(name="?", nodes={}), path, lines)
        problems = []
        errors = exc.errors()
        # a value that is neither a type name nor a mapping fails both branches of the union: name
        # the branch that was meant (the mapping's, when the value is one)
        branches = {tuple(map(str, e["loc"][:-2])) for e in errors if len(e["loc"]) > 1 and e["loc"][-2] in _SPECS}
        for error in errors:
            unknown = error["type"] in ("extra_forbidden", "unexpected_keyword_argument")
            raw = list(error["loc"])
            # a union's branch names are pydantic's, not the file's; but an unknown key is the user's own,
            # even when it happens to spell one ("EndpointSpec: ...")
            tail = raw[-1:] if unknown else []
            loc = [str(p) for p in raw[:len(raw) - len(tail)] if p not in _UNION_TAGS] + [str(p) for p in tail]
            if error["loc"] and error["loc"][-1] == "str" and tuple(map(str, error["loc"][:-1])) in branches:
                continue
            message = error["msg"].removeprefix("Value error, ")
            if unknown:
                message = _unknown_key(loc)
            elif error["type"] == "missing":
                message = f"required key {loc[-1]!r} is missing"
            elif isinstance(error.get("input"), str | int | float | bool | None) and \
                    f"not {error.get('input')!r}" not in message:
                message = f"{message}, not {error.get('input')!r}"
            problems.append(f"{loaded.where(*loc)}: {message}")
        raise ProjectError("invalid project file:\n" + "\n".join(f"  - {p}" for p in problems)) from None
    return model, lines
