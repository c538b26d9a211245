"""Bridge synthesis: what a project shares with ROS 1 and ROS 2 graphs, checked, and the bridge
nodes (``hetros_ros1_bridge``, ``hetros_ros2_bridge``) the planner adds to carry it."""

from __future__ import annotations

import os
from collections.abc import Callable

from .._errors import MessageError
from .._qos import QoS
from ..msg import TypeRegistry, normalize_typename
from ..plan import (
    ROS1_BRIDGE,
    ROS2_BRIDGE,
    SYSTEM_NODES,
    NodePlan,
    action_endpoints,
    action_topic_qos,
)
from ._model import Bridged, LoadedProject
from ._report import CheckReport


def ros1_nodes(project: LoadedProject) -> set[str]:
    """The nodes of ``kind: ros1`` targets: ROS 1 nodes, outside the hetros channels."""
    targets = project.model.targets
    return {n for n, spec in project.model.nodes.items()
            if spec.target in targets and targets[spec.target].kind == "ros1"}


def check_ros1_nodes(project: LoadedProject, nodes: set[str], types: TypeRegistry, report: CheckReport) -> None:
    """Every endpoint of a ROS 1 node must have a type ROS 1 can carry."""
    from ..transport.tcpros import Ros1ServiceType, Ros1Type

    for nname in sorted(nodes):
        spec = project.model.nodes[nname]
        for section, make in (("publish", Ros1Type), ("subscribe", Ros1Type), ("services", Ros1ServiceType),
                              ("clients", Ros1ServiceType)):
            for endpoint, typename in spec.types(section).items():
                try:
                    make(types, normalize_typename(typename, "msg" if make is Ros1Type else "srv"))
                except MessageError as exc:
                    report.errors.append(f"{project.where('nodes', nname, section, endpoint)}: node {nname} runs "
                                         f"on a ROS 1 target, so {endpoint} must be a ROS 1 type: {exc}")


def _shared_with_ros1(project: LoadedProject) -> dict[str, list[str]]:
    """What hetros nodes share with ``kind: ros1`` nodes, which the bridge then carries
    (``export``: hetros publishes or serves it, ``import``: a ROS 1 node does)."""
    ros1 = ros1_nodes(project)
    nodes = project.model.nodes

    def endpoints(section: str, in_ros1: bool) -> set[str]:
        return {e for n, spec in nodes.items() if (n in ros1) == in_ros1 for e in getattr(spec, section)}

    return {
        "export": sorted(endpoints("publish", False) & endpoints("subscribe", True)),
        "import": sorted(endpoints("publish", True) & endpoints("subscribe", False)),
        "export_services": sorted(endpoints("services", False) & endpoints("clients", True)),
        "import_services": sorted(endpoints("services", True) & endpoints("clients", False)),
    }


def bridged(project: LoadedProject) -> dict[str, Bridged]:
    """The ``external:`` graphs the project file names: ``ros1`` and ``ros2``."""
    external = project.model.external
    if external is None:
        return {}
    return {graph: spec for graph, spec in (("ros1", external.ros1), ("ros2", external.ros2)) if spec is not None}


# what the other graph must be able to carry, per kind of endpoint; raises MessageError if it cannot
Carries = Callable[[TypeRegistry, str, str], object]


def ros1_carries(types: TypeRegistry, kind: str, typename: str) -> object:
    from ..transport.tcpros import Ros1ActionType, Ros1ServiceType, Ros1Type

    return {"msg": Ros1Type, "srv": Ros1ServiceType, "action": Ros1ActionType}[kind](types, typename)


def ros2_carries(types: TypeRegistry, kind: str, typename: str) -> object:
    """Every ROS 2 type crosses, except what DDS's binding cannot describe (wstring)."""
    from ..transport.dds import idl_type

    if kind == "msg":
        return idl_type(types, typename)
    srvs = [typename] if kind == "srv" else [f"{typename}_SendGoal", f"{typename}_GetResult"]
    for srv in srvs:
        idl_type(types, f"{srv}_Request", True)
        idl_type(types, f"{srv}_Response", True)
    if kind == "action":
        idl_type(types, f"{typename}_FeedbackMessage")
    return srvs


def check_bridged(project: LoadedProject, graph: str, spec: Bridged,
                   tables: tuple[dict[str, list[tuple[str, str]]], ...], carries: Carries,
                   types: TypeRegistry, report: CheckReport) -> None:
    """Exported topics and services need hetros publishers or servers, imported ones subscribers
    or clients; every type must be one the other graph can carry."""
    publishers, subscribers, servers, clients = tables
    where = project.where
    other = "ROS 1" if graph == "ros1" else "ROS 2"
    for section, attr, table, needs in (("export", "export", publishers, "publisher"),
                                        ("import", "import_", subscribers, "subscriber")):
        for index, topic in enumerate(getattr(spec, attr)):
            here = where("external", graph, section, index)
            endpoints = table.get(topic)
            if not endpoints and section == "export" and topic in project.replayed:
                endpoints = subscribers.get(topic)  # a recording played into the launch publishes it
            if not endpoints:
                report.errors.append(f"{here}: {topic} has no hetros {needs} to {section} for; declare one "
                                     f"under a node's {'publish' if needs == 'publisher' else 'subscribe'}")
                continue
            try:
                carries(types, "msg", endpoints[0][1])
            except MessageError as exc:
                report.errors.append(f"{here}: {exc}")
    for section, table, needs, counterpart in (("export_services", servers, "server", clients),
                                               ("import_services", clients, "client", servers)):
        for index, service in enumerate(getattr(spec, section)):
            here = where("external", graph, section, index)
            endpoints = table.get(service)
            if not endpoints:
                report.errors.append(f"{here}: {service} has no hetros {needs} to "
                                     f"{section.split('_')[0]} for; declare one under a node's "
                                     f"{'services' if needs == 'server' else 'clients'}")
                continue
            if section == "import_services" and service in counterpart:
                report.errors.append(f"{here}: {service} is served by a hetros node already; import it from "
                                     f"{other} or serve it here, not both")
                continue
            try:
                carries(types, "srv", endpoints[0][1])
            except MessageError as exc:
                report.errors.append(f"{here}: {exc}")
    action_servers = {a: t for node in project.model.nodes.values() for a, t in node.types("actions").items()}
    action_clients = {a: t for node in project.model.nodes.values() for a, t in node.types("action_clients").items()}
    for section, needs, declared in (("export_actions", "server", action_servers),
                                     ("import_actions", "client", action_clients)):
        for index, action in enumerate(getattr(spec, section)):
            here = where("external", graph, section, index)
            if section == "import_actions" and action in action_servers:
                report.errors.append(f"{here}: {action} is served by a hetros node already; import it from "
                                     f"{other} or serve it here, not both")
                continue
            if action not in declared:
                report.errors.append(f"{here}: {action} has no hetros action {needs} to {section.split('_')[0]} "
                                     f"for; declare one under a node's "
                                     f"{'actions' if needs == 'server' else 'action_clients'}")
                continue
            try:
                carries(types, "action", normalize_typename(declared[action], "action"))
            except MessageError as exc:
                report.errors.append(f"{here}: {exc}")


def _typed(project: LoadedProject, shared: dict[str, list[str]]) -> tuple[dict[str, str], ...]:
    """The types of the endpoints a bridge carries: export, import (topics), export_services,
    import_services, export_actions, import_actions, each name -> full type name."""
    sections = {"msg": ("publish", "subscribe"), "srv": ("services", "clients"),
                "action": ("actions", "action_clients")}
    declared: dict[str, dict[str, str]] = {kind: {} for kind in sections}
    for node in project.model.nodes.values():
        for kind, names in sections.items():
            for section in names:
                declared[kind].update(node.types(section))
    return tuple({name: normalize_typename(declared[kind][name], kind) for name in shared.get(key, ())}
                 for key, kind in (("export", "msg"), ("import", "msg"), ("export_services", "srv"),
                                   ("import_services", "srv"), ("export_actions", "action"),
                                   ("import_actions", "action")))


def ros2_bridge(project: LoadedProject) -> NodePlan | None:
    """The node that carries what ``external: ros2:`` names to and from DDS (in the launcher's
    process). Actions cross as what they are on ROS 2's wire: three services and two topics."""
    spec = project.model.external.ros2 if project.model.external is not None else None
    if spec is None:
        return None
    shared = spec.listed()
    if not any(shared.values()):
        return None
    exports, imports, export_services, import_services, export_actions, import_actions = _typed(project, shared)
    for actions, (services, topics) in ((export_actions, (export_services, exports)),
                                        (import_actions, (import_services, imports))):
        for action, typename in actions.items():
            derived_services, derived_topics = action_endpoints(action, typename)
            services.update(derived_services)
            topics.update(derived_topics)

    def qos(topic: str) -> dict[str, object]:
        chosen = project.model.topics.get(topic) or action_topic_qos(topic) or QoS()
        return {"reliability": chosen.reliability, "history": chosen.history, "depth": chosen.depth,
                "durability": chosen.durability, "publish_timeout": chosen.publish_timeout}

    # ROS 2 tools list endpoints under nodes: a DDS writer of an exported topic under the hetros
    # nodes that publish it, a reader of an imported one under those that subscribe, and so on
    def owners(section: str, names: dict[str, str]) -> dict[str, list[str]]:
        return {name: [n for n, node in project.model.nodes.items() if name in node.types(section)] or [ROS2_BRIDGE]
                for name in names}

    parameters = {"domain": spec.domain, "interface": spec.interface, "peers": list(spec.peers),
                  "multicast": spec.multicast, "export": exports, "import": imports,
                  "export_services": export_services, "import_services": import_services,
                  "qos": {t: qos(t) for t in [*exports, *imports]},
                  "owners": {"export": owners("publish", exports), "import": owners("subscribe", imports),
                             "export_services": owners("services", export_services),
                             "import_services": owners("clients", import_services)}}
    return NodePlan(ROS2_BRIDGE, SYSTEM_NODES["ros2_bridge"], ROS2_BRIDGE, parameters,
                    publish=imports, subscribe=exports, services=import_services, clients=export_services)


def _ros1_shared(project: LoadedProject) -> dict[str, list[str]]:
    """Everything shared with ROS 1: with its ``kind: ros1`` nodes and through ``external: ros1:``."""
    model = project.model
    spec = model.external.ros1 if model.external is not None else None
    shared = _shared_with_ros1(project)
    if spec is not None:
        for key, listed in spec.listed().items():
            shared[key] = sorted(set(shared.get(key, ())) | set(listed))
    return shared


def _hardware_target(project: LoadedProject, node: str) -> str:
    """The fpga target whose hardware runs ``node`` (it has ``hw:`` and sits there), else ""."""
    spec = project.model.nodes[node]
    target = project.model.targets.get(spec.target)
    return spec.target if target is not None and target.kind == "fpga" and spec.hw else ""


def hardware_framed(project: LoadedProject) -> dict[str, tuple[tuple[str, ...], tuple[str, ...]]]:
    """Hardware TCPROS: per fpga target, ``(exports, imports)``: the ROS 1 topics its hardware frames.

    An exported topic is framed by the fpga target all of whose hetros publishers are its hardware
    nodes; an imported one by every fpga target with a hardware node subscribing. The target's gateway
    then registers with the master and moves the hardware's frames; the bridge carries the rest.
    """
    model = project.model
    shared = _ros1_shared(project)
    ros1 = ros1_nodes(project)
    framed: dict[str, tuple[list[str], list[str]]] = {}
    for topic in shared["export"]:
        publishers = {_hardware_target(project, n) for n, spec in model.nodes.items()
                      if n not in ros1 and topic in spec.publish}
        if len(publishers) == 1 and (target := publishers.pop()):
            framed.setdefault(target, ([], []))[0].append(topic)
    for topic in shared["import"]:
        for target in sorted({_hardware_target(project, n) for n, spec in model.nodes.items()
                              if n not in ros1 and topic in spec.subscribe} - {""}):
            framed.setdefault(target, ([], []))[1].append(topic)
    return {target: (tuple(exports), tuple(imports)) for target, (exports, imports) in framed.items()}


def ros1_bridge(project: LoadedProject) -> NodePlan | None:
    """The node that carries exported and imported topics across (in the launcher's process), but for
    what fpga targets frame themselves (``hardware_framed``)."""
    model = project.model
    spec = model.external.ros1 if model.external is not None else None
    shared = _ros1_shared(project)
    framed = hardware_framed(project)
    in_hardware = {t for exports, _ in framed.values() for t in exports}
    shared["export"] = [t for t in shared["export"] if t not in in_hardware]
    ros1 = ros1_nodes(project)
    shared["import"] = [t for t in shared["import"] if any(
        t in s.subscribe for n, s in model.nodes.items() if n not in ros1 and not _hardware_target(project, n))]
    if not any(shared.values()):
        return None
    exports, imports, export_services, import_services, export_actions, import_actions = _typed(project, shared)
    # the bridge is a client of exported actions and the server of imported ones
    publish, subscribe = dict(imports), dict(exports)
    services, clients = dict(import_services), dict(export_services)
    for actions, (calls, hears) in ((export_actions, (clients, subscribe)), (import_actions, (services, publish))):
        for action, typename in actions.items():
            derived_services, derived_topics = action_endpoints(action, typename)
            calls.update(derived_services)
            hears.update(derived_topics)
    # ROS 1 latching is ROS 2's transient_local: a late subscriber gets the last message
    latched = [t for t in exports if (q := model.topics.get(t)) is not None and q.keeps_history]
    host = spec.host if spec is not None else "127.0.0.1"
    parameters = {"master": ros1_master(project), "host": host, "export": exports, "import": imports,
                  "latch": latched, "ros1_name": f"/{model.name}_hetros",
                  "export_services": export_services, "import_services": import_services,
                  "export_actions": export_actions, "import_actions": import_actions}
    return NodePlan(ROS1_BRIDGE, SYSTEM_NODES["ros1_bridge"], ROS1_BRIDGE, parameters,
                    publish=publish, subscribe=subscribe, services=services, clients=clients,
                    actions=import_actions, action_clients=export_actions,
                    max_goals=dict.fromkeys(import_actions, 64))


def ros1_master(project: LoadedProject) -> str:
    external = project.model.external
    spec = external.ros1 if external is not None else None
    if spec is None and not ros1_nodes(project):
        return ""
    return (spec.master if spec is not None else None) or os.environ.get("ROS_MASTER_URI", "http://127.0.0.1:11311/")
