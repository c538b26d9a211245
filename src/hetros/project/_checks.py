"""``hetros check``: every static check of a project, each error naming its YAML path and the fix."""

from __future__ import annotations

import ast
import difflib
import hashlib
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

from .._errors import DefinitionError, MessageError, ProjectError
from .._files import parse_python
from .._net import is_local_address
from .._qos import MATCHED_POLICIES, MIN_PERIOD, QoS, delivery_conflicts, offer_falls_short
from ..msg import TypeRegistry, array_fields, flat_layout, normalize_typename, registry
from ..plan import (
    ACTION_PREFIX,
    LAUNCHER,
    ROS1_BRIDGE,
    ROS2_BRIDGE,
    process_name,
    resolve_name,
)
from ..transport import reserved_bytes
from ._bridges import (
    bridged,
    check_bridged,
    check_ros1_nodes,
    ros1_carries,
    ros1_nodes,
    ros2_carries,
)
from ._model import Bridged, LoadedProject, NodeSpec
from ._names import node_name_problem, topic_name_problem
from ._probe import hardware_problems, module_findable, runnable_problems
from ._report import CheckReport
from ._ros_scan import PLACEHOLDER, scan_ros_code, unsupported_uses, writes_ros
from ._scan import scan_file


def load_messages(project: LoadedProject, types: TypeRegistry, report: CheckReport) -> None:
    for index, folder in enumerate(project.model.messages):
        path = (project.root / folder).resolve()
        try:
            types.load_folder(path)
        except DefinitionError as exc:
            report.errors.append(f"{project.where('messages', index)}: {exc}")


def _check_placeholders(project: LoadedProject, report: CheckReport) -> bool:
    """What ``hetros init`` could not read from the code (a name built at run time) and left for the user."""
    for nname, spec in project.model.nodes.items():
        for section in ("publish", "subscribe", "services", "clients", "actions", "action_clients"):
            for endpoint, entry in getattr(spec, section).items():
                typename = entry if isinstance(entry, str) else entry.type
                for text in (endpoint, typename):
                    if text.lstrip("/").startswith(PLACEHOLDER):
                        report.errors.append(
                            f"{project.where('nodes', nname, section, endpoint)}: placeholder "
                            f"{text.lstrip('/')[1:]!r} left by `hetros init`: the code names this at run time; "
                            "replace it with the name or type it has")
    return bool(report.errors)


def _check_env(project: LoadedProject, report: CheckReport) -> None:
    """Nodes that share a process share its environment: they must not ask different values of one variable."""
    model = project.model
    asked: dict[tuple[str, str], tuple[str, str]] = {}
    for nname, spec in model.nodes.items():
        target = model.targets.get(spec.target)
        process = LAUNCHER if target is not None and target.kind == "thread" else spec.target
        for variable, value in spec.env.items():
            first = asked.setdefault((process, variable), (nname, value))
            if first[1] != value:
                report.errors.append(
                    f"{project.where('nodes', nname, 'env', variable)}: {variable}={value!r}, but node {first[0]!r} "
                    f"in the same process asks {variable}={first[1]!r}; a process has one environment: agree, or "
                    "put the nodes on targets of their own")


Endpoints = dict[str, list[tuple[str, str]]]


@dataclass
class CheckContext:
    """What the rules of ``check`` share: the project, and its endpoints gathered once (name ->
    [(node, type)]) by :func:`gather_endpoints`."""

    project: LoadedProject
    types: TypeRegistry
    report: CheckReport
    publishers: Endpoints = field(default_factory=dict)
    subscribers: Endpoints = field(default_factory=dict)
    servers: Endpoints = field(default_factory=dict)
    clients: Endpoints = field(default_factory=dict)
    runnable: dict[str, list[str]] = field(default_factory=dict)  # run: -> the nodes it runs
    derived: set[str] = field(default_factory=set)  # the services and topics of actions: checked as actions
    speaks_ros1: set[str] = field(default_factory=set)  # the nodes of kind: ros1 targets
    external: dict[str, Bridged] = field(default_factory=dict)

    def error(self, message: str) -> None:
        self.report.errors.append(message)

    def hetros_side(self, table: Endpoints) -> Endpoints:
        """``table`` without the endpoints of ROS 1 nodes (they are not hetros channels)."""
        return {k: kept for k, v in table.items() if (kept := [e for e in v if e[0] not in self.speaks_ros1])}


def check(project: LoadedProject, types: TypeRegistry | None = None) -> CheckReport:
    """Every check ``hetros check`` promises (``RULES``, in order); errors name file:line and the YAML path.

    `hetros launch` plans only what this accepts, so a rule here is one it applies too.
    """
    types = types or registry()
    report = CheckReport()
    load_messages(project, types, report)
    if _check_placeholders(project, report):
        return report  # the project is not finished: everything else would follow from the placeholders
    context = CheckContext(project, types, report, speaks_ros1=ros1_nodes(project), external=bridged(project))
    for rule in RULES:
        rule(context)
    return report


def cpus_exist(c: CheckContext) -> None:
    """A target's cpus are this machine's."""
    count = os.cpu_count() or 1
    for tname, target in c.project.model.targets.items():
        for index, cpu in enumerate(target.cpus):
            if cpu >= count:
                c.error(f"{c.project.where('targets', tname, 'cpus', index)}: cpu {cpu} does not exist on this "
                        f"machine ({count} CPUs: 0..{count - 1})")


def hosts_and_env(c: CheckContext) -> None:
    _check_hosts(c.project, c.report)
    _check_env(c.project, c.report)


def bridge_names_reserved(c: CheckContext) -> None:
    """The bridges' names are the planner's."""
    model = c.project.model
    for reserved, graph in ((ROS1_BRIDGE, "ROS 1"), (ROS2_BRIDGE, "ROS 2")):
        if reserved in model.nodes or reserved in model.targets:
            c.error(f"{c.project.where('nodes', reserved)}: {reserved!r} is reserved for the {graph} bridge; "
                    "rename the node or target")


def import_folders_exist(c: CheckContext) -> None:
    for index, folder in enumerate(c.project.model.python_path):
        if not (c.project.root / folder).is_dir():
            c.error(f"{c.project.where('python_path', index)}: {folder!r} is not a folder; python_path lists the "
                    "folders node modules are imported from, relative to the project file")


def nodes_are_well_formed(c: CheckContext) -> None:
    """Each node's target exists, its names are ROS names, its run: can be found."""
    model, where = c.project.model, c.project.where
    for nname, spec in model.nodes.items():
        if spec.target not in model.targets:
            c.error(f"{where('nodes', nname, 'target')}: unknown target {spec.target!r}; "
                    f"define it under targets (known: {', '.join(model.targets) or 'none'})")
        problem = node_name_problem(nname) or (node_name_problem(spec.name) if spec.name else None)
        if problem:
            c.error(f"{where('nodes', nname)}: {problem}")
        if spec.namespace and (problem := topic_name_problem(spec.namespace)):
            c.error(f"{where('nodes', nname, 'namespace')}: namespace {spec.namespace!r}: {problem}")
        module = spec.run.partition(":")[0]
        if ":" not in spec.run:
            if not (c.project.root / spec.run).is_file():
                c.error(f"{where('nodes', nname, 'run')}: script {spec.run!r} is not a file (looked for "
                        f"{c.project.root / spec.run}); write module:function for a node function, or a script's "
                        "path relative to the project file")
        elif not module_findable(c.project, module):
            c.error(f"{where('nodes', nname, 'run')}: module {module!r} is found neither next to the project file, "
                    "nor in its python_path: folders, nor in the environment; add the folder it is imported "
                    "from to python_path:")
        else:
            c.runnable.setdefault(spec.run, []).append(nname)
        _check_actions(c.project, nname, spec, c.types, c.report)


def gather_endpoints(c: CheckContext) -> None:
    """Every node's topics and services into the context's tables, each name and type checked."""
    where = c.project.where
    for nname, spec in c.project.model.nodes.items():
        for section, table, kind in (("publish", c.publishers, "msg"), ("subscribe", c.subscribers, "msg"),
                                     ("services", c.servers, "srv"), ("clients", c.clients, "srv")):
            for endpoint, typename in spec.types(section).items():
                if spec.action_of(section, endpoint) is not None:
                    c.derived.add(endpoint)
                    table.setdefault(endpoint, []).append((nname, normalize_typename(typename, kind)))
                    continue
                if problem := topic_name_problem(endpoint):
                    c.error(f"{where('nodes', nname, section, endpoint)}: {endpoint!r} {problem}")
                try:
                    full = normalize_typename(typename, kind)
                    if kind == "msg":
                        c.types.get(full)
                    else:
                        c.types.get_service(full)
                except MessageError as exc:
                    c.error(f"{where('nodes', nname, section, endpoint)}: {exc}")
                    full = typename
                table.setdefault(endpoint, []).append((nname, full))
        for service, typename in c.project.parameter_services_called(nname).items():
            if service not in spec.services:
                c.servers.setdefault(service, []).append((nname, typename))
        for topic, typename in c.project.lifecycle_events_heard(nname).items():
            c.publishers.setdefault(topic, []).append((nname, typename))


def code_runs(c: CheckContext) -> None:
    """Each run: imports and names a function (in a probe process), uses no ROS API hetros lacks; hardware
    tools are there."""
    where = c.project.where
    for nname, spec in c.project.model.nodes.items():
        path = _code_file(c.project, nname, spec.run)
        for problem in unsupported_uses(path) if path is not None else ():
            c.error(f"{where('nodes', nname, 'run')}: {problem}")
    for run, problem in runnable_problems(c.project, list(c.runnable)).items():
        for nname in c.runnable.get(run, []):
            c.error(f"{where('nodes', nname, 'run')}: {problem}")
    for nname, problem in hardware_problems(c.project).items():
        if nname:
            c.error(f"{where('nodes', nname, 'hw')}: {problem}")
        else:
            c.report.warnings.append(f"{where('nodes')}: {problem}; `make install-rtl` brings the tools")


def _code_file(project: LoadedProject, node: str, run: str) -> Path | None:
    """The source file a node's ``run:`` names (a script, or a module found next to the project file or in
    its python_path: folders), when it is a file there."""
    root = Path(project.node_roots.get(node) or project.root)
    if ":" not in run:
        return root / run if (root / run).is_file() else None
    for folder in (root, *project.import_folders):
        candidate = folder.joinpath(*run.partition(":")[0].split(".")).with_suffix(".py")
        if candidate.is_file():
            return candidate
    return None


def code_qos_agrees(c: CheckContext) -> None:
    """ROS code that chooses a delivery policy (reliability, durability, history) the project file's QoS of
    the topic contradicts is refused naming both: the topic's QoS is every endpoint's, and the code would
    get what it did not ask for. The launch refuses what only shows at run time the same way."""
    for nname, spec in c.project.model.nodes.items():
        path = _code_file(c.project, nname, spec.run)
        if path is None or not writes_ros(path):
            continue
        name = spec.name or nname
        remap = {resolve_name(k, spec.namespace, name): resolve_name(v, spec.namespace, name)
                 for k, v in spec.remap.items()}
        root = Path(c.project.node_roots.get(nname) or c.project.root)
        for folder in (root, *c.project.import_folders):
            if ":" in spec.run and folder.joinpath(*spec.run.partition(":")[0].split(".")).with_suffix(".py") == path:
                root = folder
                break
        found = scan_ros_code(path, spec.run, root)
        for section, names in found.endpoints.items():
            declared_names = {str(name) for name in getattr(spec, section, {})}
            for written, typename in sorted(names.items()):
                if written.startswith(PLACEHOLDER):
                    continue
                endpoint = resolve_name(written, spec.namespace, name, remap)
                if endpoint not in declared_names:
                    c.report.warnings.append(
                        f"{c.project.where('nodes', nname, section)}: the code of {nname} ({path.name}) creates "
                        f"{section} endpoint {endpoint}, which the project does not declare; the launch refuses it "
                        f"when that line runs (add '{endpoint}: {typename}' under nodes.{nname}.{section})")
        for section, topic, chosen, place in found.chosen:
            if topic.startswith(PLACEHOLDER):
                continue
            full = resolve_name(topic, spec.namespace, name, remap)
            declared = c.project.model.topics.get(full)
            conflicts = [] if declared is None else delivery_conflicts(chosen, declared, section == "subscribe")
            if conflicts:
                c.error(f"{c.project.where('topics', full)}: {place}: node {nname}'s {section} endpoint asks "
                        f"{'; '.join(conflicts)}; the topic's QoS is every endpoint's: make the two agree")


def actions_pair(c: CheckContext) -> None:
    _check_action_pairs(c.project, {a for spec in c.external.values() for a in spec.import_actions}, c.report)


def subscriptions_have_publishers(c: CheckContext) -> None:
    """A subscribed topic with no publisher here, in an import or in a recording is a warning, not an error:
    ROS lets a subscriber wait (for `hetros topic pub`, a recording played later, a peer), but a typo in
    a topic name looks the same, so the nearest published name is offered."""
    imported = {t for spec in c.external.values() for t in spec.import_} | c.project.replayed
    for topic, subscribed in c.subscribers.items():
        if topic in c.derived or topic in c.publishers or topic in imported:
            continue
        for nname, _ in subscribed:
            if nname in c.speaks_ros1:
                continue  # a ROS 1 node's topic may come from any ROS 1 publisher
            c.report.warnings.append(
                f"{c.project.where('nodes', nname, 'subscribe', topic)}: nobody in the project publishes {topic}"
                f"{_nearest(topic, c.publishers)}; the subscription waits (for `hetros topic pub`, a recording or "
                "a peer); to hear a ROS 1 or ROS 2 publisher, import the topic (external: ros1: / ros2: import:)")


def one_type_per_topic(c: CheckContext) -> None:
    for topic in (set(c.publishers) | set(c.subscribers)) - c.derived:
        endpoints = c.publishers.get(topic, []) + c.subscribers.get(topic, [])
        if len({t for _, t in endpoints}) > 1:
            users = ", ".join(f"{n}: {t}" for n, t in endpoints)
            c.error(f"{c.project.where('nodes')}: topic {topic} is declared with different types ({users}); one "
                    "topic carries one type")


def clients_have_servers(c: CheckContext) -> None:
    imported = {v for spec in c.external.values() for v in spec.import_services}
    for service, calling in c.clients.items():
        if service in c.derived or service in c.servers or service in imported:
            continue
        for nname, _ in calling:
            if nname in c.speaks_ros1:
                continue  # a ROS 1 node may call any ROS 1 service
            c.error(f"{c.project.where('nodes', nname, 'clients', service)}: no node serves "
                    f"{service}{_nearest(service, c.servers)}; add it under some node's 'services'")


def one_server_one_type_per_service(c: CheckContext) -> None:
    where = c.project.where
    for service, serving in c.servers.items():
        if service in c.derived:
            continue
        if len(serving) > 1:
            c.error(f"{where('nodes', serving[1][0], 'services', service)}: {service} is already served by "
                    f"{serving[0][0]}; a service has one server")
        if len({t for _, t in serving + c.clients.get(service, [])}) > 1:
            c.error(f"{where('nodes')}: service {service} is declared with different types")


def topic_entries_are_used(c: CheckContext) -> None:
    """Each topics: entry names a topic of the graph, with a QoS that means what it says."""
    where = c.project.where
    for topic, topic_spec in c.project.model.topics.items():
        if problem := topic_name_problem(topic):
            c.error(f"{where('topics', topic)}: {topic!r} {problem}")
        if topic not in c.publishers and topic not in c.subscribers:
            c.error(f"{where('topics', topic)}: no node publishes or subscribes {topic}")
        if topic_spec.reliability == "best_effort" and topic_spec.history == "keep_all":
            c.report.warnings.append(f"{where('topics', topic)}: best_effort never blocks, so keep_all behaves like "
                                     "keep_last with this depth")


def qos_compatible(c: CheckContext) -> None:
    _check_qos_compatibility(c.project, c.publishers, c.subscribers, c.report)


def hardware_topics(c: CheckContext) -> None:
    _check_hardware_topics(c.project, c.publishers, c.subscribers, c.types, c.report)


def shm_within_budget(c: CheckContext) -> None:
    _check_shm_budget(c.project, c.types, c.hetros_side(c.publishers), c.hetros_side(c.subscribers), c.report)


def ros1_nodes_fit(c: CheckContext) -> None:
    if c.speaks_ros1:
        check_ros1_nodes(c.project, c.speaks_ros1, c.types, c.report)


def sources_exist(c: CheckContext) -> None:
    _check_sources(c.project, c.report)


def bridged_endpoints_fit(c: CheckContext) -> None:
    tables = (c.publishers, c.subscribers, c.servers, c.clients)
    for graph, bridged_spec in c.external.items():
        check_bridged(c.project, graph, bridged_spec, tables, ros1_carries if graph == "ros1" else ros2_carries,
                      c.types, c.report)


def chains_name_topics(c: CheckContext) -> None:
    """A chain's first and last topics are topics of the graph."""
    known = set(c.publishers) | set(c.subscribers)
    for name, chain in c.project.model.chains.items():
        for key in ("first", "last"):
            topic = getattr(chain, key)
            if topic not in known:
                c.error(f"{c.project.where('chains', name, key)}: no node publishes or subscribes {topic}"
                        f"{_nearest(topic, known)}; a chain runs from one topic of the graph to "
                        "another")


_TIMING_CALLS = {"rate": "a rate", "create_rate": "a rate", "Rate": "a rate", "create_timer": "a timer's period",
                 "Timer": "a timer's period"}


def _timing_parameters(tree: ast.AST) -> dict[str, tuple[str, int]]:
    """The parameters (by name) whose value the code passes to a rate or a timer, with what it passes it to
    and the line: ``node.rate(node.get_parameter('hz'))``, or through a name assigned from one."""
    def asked(expression: ast.AST) -> set[str]:
        return {call.args[0].value for call in ast.walk(expression)
                if isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute | ast.Name)
                and (call.func.attr if isinstance(call.func, ast.Attribute) else call.func.id) in
                ("get_parameter", "get_param", "declare_parameter") and call.args
                and isinstance(call.args[0], ast.Constant) and isinstance(call.args[0].value, str)}
    holding: dict[str, set[str]] = {}  # a local name -> the parameters its value came from
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign | ast.AnnAssign) and node.value is not None:
            names = asked(node.value)
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if isinstance(target, ast.Name) and names:
                    holding.setdefault(target.id, set()).update(names)
                elif isinstance(target, ast.Attribute) and names:
                    holding.setdefault(target.attr, set()).update(names)
    found: dict[str, tuple[str, int]] = {}
    for call in ast.walk(tree):
        if not isinstance(call, ast.Call) or not call.args:
            continue
        name = call.func.attr if isinstance(call.func, ast.Attribute) else \
            call.func.id if isinstance(call.func, ast.Name) else None
        if name not in _TIMING_CALLS:
            continue
        used = asked(call.args[0])
        for part in ast.walk(call.args[0]):
            key = part.id if isinstance(part, ast.Name) else part.attr if isinstance(part, ast.Attribute) else None
            used |= holding.get(key or "", set())
        for parameter in used:
            found.setdefault(parameter, (f"{name}()", call.lineno))
    return found


def timing_parameters_are_numbers(c: CheckContext) -> None:
    """A parameter the code passes to a rate or a timer must be a finite number a rate or period can be: the
    launch would refuse 'fast', NaN, 0, -5 or 1e-320 at that call, so check refuses them first."""
    for nname, spec in c.project.model.nodes.items():
        if not spec.parameters:
            continue
        path = _code_file(c.project, nname, spec.run)
        if path is None:
            continue
        try:
            tree = parse_python(path, "node source", error=ProjectError)
        except ProjectError:
            continue  # code_runs reports it
        for parameter, (call, line) in sorted(_timing_parameters(tree).items()):
            if parameter not in spec.parameters:
                continue
            value = spec.parameters[parameter]
            if isinstance(value, bool) or not isinstance(value, int | float) or \
                    not (MIN_PERIOD <= value <= 1 / MIN_PERIOD):
                c.error(f"{c.project.where('nodes', nname, 'parameters', parameter)}: the code of {nname} "
                        f"({path.name}:{line}) passes {parameter} to {call}, which takes a finite number from "
                        f"{MIN_PERIOD:g} to {1 / MIN_PERIOD:g}, not {value!r}")


# the order matters where a rule reads what an earlier one gathered (gather_endpoints, nodes_are_well_formed)
RULES: tuple[Callable[[CheckContext], None], ...] = (
    cpus_exist, hosts_and_env, bridge_names_reserved, import_folders_exist, nodes_are_well_formed,
    gather_endpoints, code_runs, code_qos_agrees, actions_pair, subscriptions_have_publishers, one_type_per_topic,
    clients_have_servers, one_server_one_type_per_service, topic_entries_are_used, qos_compatible, hardware_topics,
    shm_within_budget, ros1_nodes_fit, sources_exist, bridged_endpoints_fit, chains_name_topics,
    timing_parameters_are_numbers,
)


def _check_hosts(project: LoadedProject, report: CheckReport) -> None:
    """Host names become parts of DDS topic names; targets name hosts that exist; one address each."""
    model = project.model
    where = project.where
    ros2 = model.external.ros2 if model.external is not None else None
    if model.hosts and ros2 is not None and (model.dds_domain is None or model.dds_domain == ros2.domain):
        # one process holds one Cyclone configuration per domain: the bridge would take the hosts' one
        report.errors.append(f"{where('dds_domain')}: the edges between hosts and external: ros2: need different "
                             "DDS domains (their participants are configured differently); set dds_domain: and "
                             "external: ros2: domain: to two numbers")
    for name, host in model.hosts.items():
        if not name.isidentifier():
            report.errors.append(f"{where('hosts', name)}: a host name must be letters, digits and '_' "
                                 f"(it is part of DDS topic names), not {name!r}")
        users = [other for other, spec in model.hosts.items() if spec.address == host.address]
        if users[0] != name:
            report.errors.append(f"{where('hosts', name, 'address')}: {host.address} is host {users[0]}'s "
                                 "address already; one machine is one host (targets share it)")
    if model.hosts and not any(is_local_address(host.address) for host in model.hosts.values()):
        report.warnings.append(f"{where('hosts')}: none of the hosts' addresses ("
                               f"{', '.join(h.address for h in model.hosts.values())}) is this machine's: "
                               "`hetros launch` runs on one of the hosts (edit an address if this machine is one)")
    custom_dds = bool(os.environ.get("CYCLONEDDS_URI"))
    if ros2 is not None and not custom_dds and not is_local_address(ros2.interface):
        report.errors.append(f"{where('external', 'ros2', 'interface')}: {ros2.interface} is not an address of "
                             "this machine, so the ROS 2 bridge's DDS participant cannot use it; give one of this "
                             "machine's addresses (127.0.0.1 for ROS 2 nodes on this machine)")
    for tname, target in model.targets.items():
        if target.sim is not None and target.kind != "fpga":
            report.errors.append(f"{where('targets', tname, 'sim')}: only an fpga target runs in a simulator; "
                                 f"remove sim: from this {target.kind} target")
        if target.host is None:
            continue
        if not model.hosts:
            report.errors.append(f"{where('targets', tname, 'host')}: host {target.host!r} is not defined; "
                                 "name the machines under hosts: (name: {address: ...})")
        elif target.host not in model.hosts:
            report.errors.append(f"{where('targets', tname, 'host')}: unknown host {target.host!r}; define it "
                                 f"under hosts: (known: {', '.join(model.hosts)})")
        elif target.kind == "fpga" and len(model.hosts) > 1:
            report.warnings.append(f"{where('targets', tname, 'host')}: an fpga target's topic network is "
                                   "generated per target; its host only decides where its software side runs")


def project_hash(project: LoadedProject) -> str:
    """Of the project file and every message definition it loads: hosts compare it when they meet."""
    digest = hashlib.sha256(project.path.read_bytes())
    for folder in project.model.messages:
        root = (project.root / folder).resolve()
        for path in sorted(p for p in root.rglob("*") if p.is_file() and p.suffix in (".msg", ".srv", ".action")):
            digest.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


_HW_QOS = {"reliability": "reliable", "history": "keep_all", "durability": "volatile"}


def _check_hardware_topics(project: LoadedProject, publishers: dict[str, list[tuple[str, str]]],
                           subscribers: dict[str, list[tuple[str, str]]], types: TypeRegistry,
                           report: CheckReport) -> None:
    """A topic is a hardware topic when all its endpoints sit on one fpga target; say why when not."""
    model = project.model
    where = project.where
    fpga = {t for t, spec in model.targets.items() if spec.kind == "fpga"}
    for nname, spec in model.nodes.items():
        if spec.target in fpga and not spec.hw:  # the rule `hetros launch` applies before it starts
            report.warnings.append(f"{where('nodes', nname, 'target')}: node {nname} sits on fpga target "
                                   f"{spec.target} without a hardware implementation, so `hetros launch` will refuse "
                                   "the project (`hetros hw build` makes its topic network all the same): give it a "
                                   "hw: (module:Component, see hetros.hw.nodes) or move it to a process target")
        if spec.target in fpga:
            for section in ("clients", "actions", "action_clients"):
                for name in getattr(spec, section):
                    report.errors.append(f"{where('nodes', nname, section, name)}: {section} of a node on an fpga "
                                         "target are not carried by hetros's gateways yet (topics and services "
                                         "are); move the node to a thread or process target")
    for nname, spec in model.nodes.items():
        _check_memory(project, nname, spec, fpga, publishers, subscribers, types, report)
    for topic in sorted(set(publishers) | set(subscribers)):
        endpoints = publishers.get(topic, []) + subscribers.get(topic, [])
        placed = {n: model.nodes[n].target for n, _ in endpoints if n in model.nodes}
        on_fpga = {n: t for n, t in placed.items() if t in fpga}
        qos = model.topics.get(topic)
        if not on_fpga:
            if qos is not None and qos.hw_fifo is not None:
                report.warnings.append(f"{where('topics', topic, 'hw_fifo')}: {topic} is not a hardware topic (no "
                                       "endpoint on an fpga target), so hw_fifo has no effect")
            continue
        crosses = len(set(on_fpga.values())) > 1 or len(on_fpga) < len(placed)
        if qos is not None and not crosses:
            for key, wanted in _HW_QOS.items():
                if getattr(qos, key) != wanted:
                    report.errors.append(f"{where('topics', topic, key)}: {topic} is a hardware topic, which is "
                                         f"reliable, keep_all and volatile (an AXI-Stream network with "
                                         f"back-pressure), not {key} {getattr(qos, key)}; remove the setting")
        if qos is not None and crosses and qos.durability == "transient_local":
            report.errors.append(f"{where('topics', topic, 'durability')}: {topic} crosses between software and "
                                 "hardware through a gateway, and hardware keeps no history for late joiners; "
                                 "make it volatile")



def _check_memory(project: LoadedProject, nname: str, spec: NodeSpec, fpga: set[str],
                  publishers: dict[str, list[tuple[str, str]]], subscribers: dict[str, list[tuple[str, str]]],
                  types: TypeRegistry, report: CheckReport) -> None:
    """``memory:``: a hardware node on an fpga target, one subscribed and one published topic of one type with
    an array, and no other hardware node on them (they carry descriptors, not messages)."""
    if not spec.memory:
        return
    here = project.where("nodes", nname, "memory")
    if spec.target not in fpga or not spec.hw:
        report.errors.append(f"{here}: memory: is for a hardware node (hw:) on an fpga target; node {nname} is not one")
        return
    reads = [t for t in spec.memory if t in spec.subscribe]
    writes = [t for t in spec.memory if t in spec.publish]
    strays = [t for t in spec.memory if t not in spec.subscribe and t not in spec.publish]
    if strays:
        report.errors.append(f"{here}: {', '.join(strays)} must be topics node {nname} subscribes or publishes")
        return
    if len(reads) != 1 or len(writes) != 1:
        report.errors.append(f"{here}: memory: names one topic the node subscribes (read in memory) and one it "
                             f"publishes (written in memory), not {len(reads)} and {len(writes)}")
        return
    read_type, write_type = spec.types("subscribe")[reads[0]], spec.types("publish")[writes[0]]
    if normalize_typename(read_type) != normalize_typename(write_type):
        report.errors.append(f"{here}: {reads[0]} ({read_type}) and {writes[0]} ({write_type}) must have one type: "
                             "the written message has the read one's shape")
        return
    if not [f for f in array_fields(types, normalize_typename(read_type)) if f.length is None]:
        report.errors.append(f"{here}: {read_type} has no array of numbers to read in memory; stream it instead")
    for topic in (*reads, *writes):
        others = {n for n, _ in publishers.get(topic, []) + subscribers.get(topic, [])
                  if n != nname and n in project.model.nodes and project.model.nodes[n].target == spec.target}
        if others:
            report.errors.append(f"{here}: {topic} carries descriptors on {spec.target}, so no other node of the "
                                 f"target may use it ({', '.join(sorted(others))} does)")


def _check_actions(project: LoadedProject, nname: str, spec: NodeSpec, types: TypeRegistry,
                   report: CheckReport) -> None:
    where = project.where
    for section in ("actions", "action_clients"):
        for action, typename in spec.types(section).items():
            problem = topic_name_problem(action)
            if problem:
                report.errors.append(f"{where('nodes', nname, section, action)}: {action!r} {problem}")
            elif ACTION_PREFIX in action + "/":
                report.errors.append(f"{where('nodes', nname, section, action)}: an action name cannot contain "
                                     f"{ACTION_PREFIX.rstrip('/')!r} (hetros puts the action's own services there)")
            try:
                types.get_action(normalize_typename(typename, "action"))
            except MessageError as exc:
                report.errors.append(f"{where('nodes', nname, section, action)}: {exc}")
            if spec.target in project.model.targets and project.model.targets[spec.target].kind == "ros1":
                report.errors.append(f"{where('nodes', nname, section, action)}: actions on a 'kind: ros1' target "
                                     "(actionlib) are not supported yet; put the node on a thread or process "
                                     "target")


def _check_action_pairs(project: LoadedProject, imported: set[str], report: CheckReport) -> None:
    """One server per action, a server (here or imported from ROS 1) for every client, one type per action."""
    where = project.where
    servers: dict[str, list[tuple[str, str]]] = {}
    for nname, spec in project.model.nodes.items():
        for action, typename in spec.types("actions").items():
            servers.setdefault(action, []).append((nname, typename))
    for action, serving in servers.items():
        if len(serving) > 1:
            report.errors.append(f"{where('nodes', serving[1][0], 'actions', action)}: action {action} is already "
                                 f"served by {serving[0][0]}; an action has one server")
    for nname, spec in project.model.nodes.items():
        for action, typename in spec.types("action_clients").items():
            if action in imported and action not in servers:
                continue
            if action not in servers:
                report.errors.append(f"{where('nodes', nname, 'action_clients', action)}: no node serves action "
                                     f"{action}; add it under some node's 'actions'")
                continue
            mine = _action_type_or_raw(typename)
            theirs = _action_type_or_raw(servers[action][0][1])
            if mine != theirs:
                report.errors.append(f"{where('nodes', nname, 'action_clients', action)}: {action} is served by "
                                     f"{servers[action][0][0]} as {theirs}, not {mine}; one action has one type")


def _action_type_or_raw(typename: str) -> str:
    try:
        return normalize_typename(typename, "action")
    except MessageError:
        return typename


def _check_shm_budget(project: LoadedProject, types: TypeRegistry, publishers: dict[str, list[tuple[str, str]]],
                      subscribers: dict[str, list[tuple[str, str]]], report: CheckReport) -> None:
    """Refuse a topic whose shared memory (iceoryx2 reserves it up front) exceeds the project's budget."""
    model = project.model
    budget = model.shm_budget_bytes

    def process(node: str) -> str:
        name = model.nodes[node].target
        target = model.targets.get(name)
        return process_name(name, target.kind if target is not None else "thread")

    for topic, published in publishers.items():
        if not any(process(p) != process(s) for p, _ in published for s, _ in subscribers.get(topic, [])):
            continue
        typename = published[0][1]
        spec = model.topics.get(topic)
        qos = spec if spec is not None else QoS()
        try:
            size = flat_layout(types, typename).size
        except MessageError:
            continue
        need = reserved_bytes(qos, size) * len({process(p) for p, _ in published})
        if need > budget:
            what = f"{size}-byte messages" if size is not None else "variable-size messages (4 KiB slots at first)"
            report.errors.append(
                f"{project.where('topics', topic, 'depth') if spec else project.where('nodes')}: {topic} would "
                f"reserve {need / 2**20:,.0f} MiB of shared memory (depth {qos.depth}, {what}) but the "
                f"project's shm_budget is {budget / 2**20:,.0f} MiB; lower the depth or raise shm_budget"
            )


def _check_qos_compatibility(project: LoadedProject, publishers: dict[str, list[tuple[str, str]]],
                             subscribers: dict[str, list[tuple[str, str]]], report: CheckReport) -> None:
    """A subscriber may not request more than a publisher offers, as ROS 2 matches them:
    reliability, durability and liveliness kind by strength, deadline and lease_duration by
    period (an offered period longer than the requested one, or none, falls short)."""
    model = project.model
    for topic, subscribed in subscribers.items():
        topic_qos = model.topics.get(topic) or QoS()
        for policy in MATCHED_POLICIES:
            default = getattr(topic_qos, policy)

            def effective(node: str, section: str, policy: str = policy, default: object = default,
                          topic: str = topic) -> object:
                spec = model.nodes[node].endpoint(section, topic)
                value = getattr(spec, policy) if spec else None
                return default if value is None else value

            def shown(value: object, policy: str = policy) -> str:
                periodic = policy in ("deadline", "lease_duration")
                return ("none" if value is None else f"{value:g} s") if periodic else str(value)

            offers = [(pub, effective(pub, "publish"), project.where("nodes", pub, "publish", topic))
                      for pub, _ in publishers.get(topic, [])]
            if topic in project.replayed:  # the player offers the topic's QoS (a --qos-profile-overrides-path's)
                offers.append(("the recording played into it", default, project.where("topics", topic)))
            for pub, offered, where in offers:
                for sub, _ in subscribed:
                    requested = effective(sub, "subscribe")
                    if offer_falls_short(policy, offered, requested):
                        report.errors.append(
                            f"{project.where('nodes', sub, 'subscribe', topic)}: incompatible QoS on "
                            f"{topic}: {sub} requests {policy} {shown(requested)} but {pub} offers "
                            f"{shown(offered)} ({where}); make them agree"
                        )


def _nearest(name: str, known: Iterable[str]) -> str:
    """ "; did you mean '/x'?" when one of ``known`` is close to ``name``, else ""."""
    near = difflib.get_close_matches(name, [str(k) for k in known], n=1, cutoff=0.6)
    return f"; did you mean {near[0]!r}?" if near else ""


_SCANNED_KIND = {"publish": "msg", "subscribe": "msg", "services": "srv", "clients": "srv", "actions": "action",
                 "action_clients": "action"}


def _check_sources(project: LoadedProject, report: CheckReport) -> None:
    """What a node's code creates against what its project entry declares: every endpoint, with
    its type where the code names it through ``hetros.interfaces``."""
    for nname, spec in project.model.nodes.items():
        module, _, attr = spec.run.partition(":")
        path = project.root.joinpath(*module.split(".")).with_suffix(".py")
        if not path.is_file():
            continue
        try:
            scanned = {s.name: s for s in scan_file(path, module)}
        except SyntaxError as exc:
            report.errors.append(f"{project.where('nodes', nname, 'run')}: {path}:{exc.lineno}: "
                                 f"syntax error: {exc.msg}")
            continue
        found = scanned.get(attr)
        if found is None:
            continue
        for section, endpoints in found.endpoints.items():
            declared = {name: typename for name, typename in getattr(spec, section).items()}
            for written, code_type in endpoints.items():
                at = f"{path.name}:{found.lines.get((section, written), found.line)}"
                endpoint = resolve_name(written, spec.namespace, spec.name or nname, spec.remap)
                if endpoint not in declared:
                    report.errors.append(
                        f"{project.where('nodes', nname, section)}: the code of {nname} ({at}) creates "
                        f"{section} endpoint {endpoint} that the project does not declare"
                        f"{_nearest(endpoint, declared)} (add '{written}: {code_type}' here otherwise)")
                    continue
                entry = declared[endpoint]
                wanted = entry if isinstance(entry, str) else entry.type
                if code_type.count("/") != 2:
                    continue  # a type the scan cannot resolve (not imported from hetros.interfaces)
                try:
                    same = normalize_typename(wanted, _SCANNED_KIND[section]) == code_type
                except MessageError:
                    continue  # the declared type's own error is reported where types are checked
                if not same:
                    report.errors.append(
                        f"{project.where('nodes', nname, section, endpoint)}: the code of {nname} ({at}) uses "
                        f"{code_type} on {endpoint}, but the project declares {wanted}; make them agree "
                        "(launch would refuse the endpoint)")
