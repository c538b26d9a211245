"""From a validated project to the plan: every check first, then one transport per edge."""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from .._errors import CheckError, DefinitionError, MessageError
from ..msg import TypeRegistry, flat_layout, normalize_typename, registry
from ..plan import (
    ACTION_PREFIX,
    LAUNCHER,
    ROS2_BRIDGE,
    SERVICE_QOS,
    ChannelPlan,
    EdgePlan,
    HostPlan,
    NodePlan,
    Plan,
    TargetPlan,
    TransportKind,
    action_endpoints,
    action_topic_qos,
    process_name,
    reply_channel,
    request_channel,
)
from ..transport import QoS, reserved_bytes
from ._model import Bridged, LoadedProject, NodeSpec, load_project
from ._names import node_name_problem, topic_name_problem
from ._scan import scan_file


@dataclass
class CheckReport:
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def load_messages(project: LoadedProject, types: TypeRegistry, report: CheckReport) -> None:
    for index, folder in enumerate(project.model.messages):
        path = (project.root / folder).resolve()
        try:
            types.load_folder(path)
        except DefinitionError as exc:
            report.errors.append(f"{project.where('messages', index)}: {exc}")


def _module_findable(project: LoadedProject, module: str) -> bool:
    candidate = project.root.joinpath(*module.split("."))
    if candidate.with_suffix(".py").is_file() or (candidate / "__init__.py").is_file():
        return True
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def check(project: LoadedProject, types: TypeRegistry | None = None) -> CheckReport:
    """Every check ``hetros check`` promises; errors name file:line and the YAML path."""
    types = types or registry()
    report = CheckReport()
    model = project.model
    load_messages(project, types, report)
    where = project.where

    for tname, target in model.targets.items():
        for index, cpu in enumerate(target.cpus):
            if cpu >= (os.cpu_count() or 1):
                report.errors.append(
                    f"{where('targets', tname, 'cpus', index)}: cpu {cpu} does not exist on this "
                    f"machine ({os.cpu_count()} CPUs: 0..{(os.cpu_count() or 1) - 1})"
                )
    _check_hosts(project, report)
    speaks_ros1 = _ros1_nodes(project)
    for reserved, graph in ((ROS1_BRIDGE, "ROS 1"), (ROS2_BRIDGE, "ROS 2")):
        if reserved in model.nodes or reserved in model.targets:
            report.errors.append(f"{where('nodes', reserved)}: {reserved!r} is reserved for the {graph} bridge; "
                                 "rename the node or target")
    publishers: dict[str, list[tuple[str, str]]] = {}
    subscribers: dict[str, list[tuple[str, str]]] = {}
    servers: dict[str, list[tuple[str, str]]] = {}
    clients: dict[str, list[tuple[str, str]]] = {}
    runnable: dict[str, list[str]] = {}
    derived: set[str] = set()  # the services and topics of actions: checked as actions
    for nname, spec in model.nodes.items():
        if spec.target not in model.targets:
            report.errors.append(
                f"{where('nodes', nname, 'target')}: unknown target {spec.target!r}; "
                f"define it under targets (known: {', '.join(model.targets) or 'none'})"
            )
        problem = node_name_problem(nname)
        if problem:
            report.errors.append(f"{where('nodes', nname)}: {problem}")
        module = spec.run.partition(":")[0]
        if not _module_findable(project, module):
            report.errors.append(
                f"{where('nodes', nname, 'run')}: module {module!r} is found neither next to the "
                "project file nor in the environment"
            )
        else:
            runnable.setdefault(spec.run, []).append(nname)
        _check_actions(project, nname, spec, types, report)
        for section, table, kind in (("publish", publishers, "msg"), ("subscribe", subscribers, "msg"),
                                     ("services", servers, "srv"), ("clients", clients, "srv")):
            for endpoint, typename in spec.types(section).items():
                if spec.action_of(section, endpoint) is not None:
                    derived.add(endpoint)
                    table.setdefault(endpoint, []).append((nname, normalize_typename(typename, kind)))
                    continue
                problem = topic_name_problem(endpoint)
                if problem:
                    report.errors.append(f"{where('nodes', nname, section, endpoint)}: {endpoint!r} {problem}")
                try:
                    full = normalize_typename(typename, kind)
                    if kind == "msg":
                        types.get(full)
                    else:
                        types.get_service(full)
                except MessageError as exc:
                    report.errors.append(f"{where('nodes', nname, section, endpoint)}: {exc}")
                    full = typename
                table.setdefault(endpoint, []).append((nname, full))

    for run, problem in _runnable_problems(project, list(runnable)).items():
        for nname in runnable.get(run, []):
            report.errors.append(f"{where('nodes', nname, 'run')}: {problem}")
    bridged = _bridged(project)
    imported = {t for spec in bridged.values() for t in spec.import_}
    _check_action_pairs(project, {a for spec in bridged.values() for a in spec.import_actions}, report)
    for topic, subscribed in subscribers.items():
        if topic in derived:
            continue
        if topic not in publishers and topic not in imported:
            for nname, _ in subscribed:
                if nname in speaks_ros1:
                    continue  # a ROS 1 node's topic may come from any ROS 1 publisher
                report.errors.append(
                    f"{where('nodes', nname, 'subscribe', topic)}: nobody publishes {topic}; "
                    "add a publisher under some node's 'publish', import it from ROS 1 or ROS 2 "
                    "(external: ros1: / ros2: import:) or remove this subscription"
                )
    for topic in (set(publishers) | set(subscribers)) - derived:
        declared = {t for _, t in publishers.get(topic, []) + subscribers.get(topic, [])}
        if len(declared) > 1:
            users = ", ".join(f"{n}: {t}" for n, t in publishers.get(topic, []) + subscribers.get(topic, []))
            report.errors.append(f"{where('nodes')}: topic {topic} is declared with different types "
                                 f"({users}); one topic carries one type")
    imported_services = {v for spec in bridged.values() for v in spec.import_services}
    for service, calling in clients.items():
        if service in derived:
            continue
        if service not in servers and service not in imported_services:
            for nname, _ in calling:
                if nname in speaks_ros1:
                    continue  # a ROS 1 node may call any ROS 1 service
                report.errors.append(f"{where('nodes', nname, 'clients', service)}: no node serves "
                                     f"{service}; add it under some node's 'services'")
    for service, serving in servers.items():
        if service in derived:
            continue
        if len(serving) > 1:
            report.errors.append(f"{where('nodes', serving[1][0], 'services', service)}: {service} is "
                                 f"already served by {serving[0][0]}; a service has one server")
        declared = {t for _, t in serving + clients.get(service, [])}
        if len(declared) > 1:
            report.errors.append(f"{where('nodes')}: service {service} is declared with different types")
    for topic, topic_spec in model.topics.items():
        problem = topic_name_problem(topic)
        if problem:
            report.errors.append(f"{where('topics', topic)}: {topic!r} {problem}")
        if topic not in publishers and topic not in subscribers:
            report.errors.append(f"{where('topics', topic)}: no node publishes or subscribes {topic}")
        if topic_spec.reliability == "best_effort" and topic_spec.history == "keep_all":
            report.warnings.append(f"{where('topics', topic)}: best_effort never blocks, so keep_all "
                                   "behaves like keep_last with this depth")
    _check_qos_compatibility(project, publishers, subscribers, report)
    _check_hardware_topics(project, publishers, subscribers, types, report)

    def hetros_side(table: dict[str, list[tuple[str, str]]]) -> dict[str, list[tuple[str, str]]]:
        return {k: kept for k, v in table.items() if (kept := [e for e in v if e[0] not in speaks_ros1])}

    _check_shm_budget(project, types, hetros_side(publishers), hetros_side(subscribers), report)
    if speaks_ros1:
        _check_ros1_nodes(project, speaks_ros1, types, report)
    _check_sources(project, report)
    tables = (publishers, subscribers, servers, clients)
    for graph, bridged_spec in bridged.items():
        _check_bridged(project, graph, bridged_spec, tables, _ros1_carries if graph == "ros1" else _ros2_carries,
                       types, report)
    return report


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
    for tname, target in model.targets.items():
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
    from ..hw import stream_problem

    model = project.model
    where = project.where
    fpga = {t for t, spec in model.targets.items() if spec.kind == "fpga"}
    for nname, spec in model.nodes.items():
        if spec.target in fpga:
            for section in ("services", "clients", "actions", "action_clients"):
                for name in getattr(spec, section):
                    report.errors.append(f"{where('nodes', nname, section, name)}: {section} of a node on an fpga "
                                         "target need a hardware/software gateway (FPGA part 2, not built yet); "
                                         "move the node to a thread or process target")
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
        software = {n: t for n, t in placed.items() if t not in fpga}
        if software or len(set(on_fpga.values())) > 1:
            hardware = ", ".join(f"{n} on {t}" for n, t in on_fpga.items())
            other = ", ".join(f"{n} on {t}" for n, t in software.items()) or "others on another fpga target"
            report.errors.append(f"{where('nodes')}: topic {topic} is not a hardware topic: {hardware} but {other}; "
                                 "an edge between hardware and software (or two fpga targets) needs a gateway "
                                 "(FPGA part 2, not built yet): put all its endpoints on one fpga target or none")
            continue
        if qos is not None:
            for key, wanted in _HW_QOS.items():
                if getattr(qos, key) != wanted:
                    report.errors.append(f"{where('topics', topic, key)}: {topic} is a hardware topic, which is "
                                         f"reliable, keep_all and volatile (an AXI-Stream network with "
                                         f"back-pressure), not {key} {getattr(qos, key)}; remove the setting")
        node, typename = endpoints[0]
        try:
            problem = stream_problem(types, typename)
        except MessageError:
            continue  # an unknown type is reported where it is declared
        if problem:
            section = "publish" if topic in publishers else "subscribe"
            report.errors.append(f"{where('nodes', node, section, topic)}: {topic} [{typename}] cannot be a "
                                 f"hardware topic: {problem}")


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


_PROBE = """
import importlib, json, sys
from pathlib import Path
from hetros.msg import registry
types = registry()
for folder in json.loads(sys.argv[2]):
    types.load_folder(Path(folder))
out = {}
for run in json.loads(sys.argv[1]):
    module_name, _, attr = run.partition(":")
    try:
        module = importlib.import_module(module_name)
    except BaseException as exc:
        tb = exc.__traceback__
        while tb is not None and tb.tb_next is not None:
            tb = tb.tb_next
        place = f" ({tb.tb_frame.f_code.co_filename}:{tb.tb_lineno})" if tb is not None else ""
        out[run] = f"importing {module_name!r} raised {type(exc).__name__}: {exc}{place}; fix the module"
        continue
    target = getattr(module, attr, None)
    if target is None:
        out[run] = f"module {module_name!r} has no {attr!r}; define it or fix 'run: {run}'"
    elif not callable(target):
        out[run] = f"{run} must be a function or class taking the node, not {type(target).__name__}"
print("\\n" + sys.argv[3] + json.dumps(out))
"""
# the probe's answer line starts with this: a node module that prints, or ends the interpreter
# at import, cannot be taken for the answer
_PROBE_MARK = "hetros-probe-result: "
_probed: dict[tuple[str, tuple[str, ...], tuple[float, ...]], dict[str, str]] = {}


def _runnable_problems(project: LoadedProject, runs: list[str]) -> dict[str, str]:
    """Import every node module as the launch will, in a separate interpreter, and find the nodes.

    A separate process keeps the user's import-time code (and module names that differ
    between projects, like many a ``nodes``) out of the checking process.
    """
    if not runs:
        return {}
    root = str(project.root.resolve())
    stamps = tuple(p.stat().st_mtime for p in sorted(project.root.glob("**/*.py")))
    key = (root, tuple(sorted(runs)), stamps)
    if key in _probed:
        return _probed[key]
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [root, env.get("PYTHONPATH", "")]))
    try:
        folders = [str((project.root / m).resolve()) for m in project.model.messages]
        done = subprocess.run([sys.executable, "-c", _PROBE, json.dumps(sorted(runs)), json.dumps(folders),
                               _PROBE_MARK], capture_output=True,
                              text=True, timeout=60, env=env, cwd=root, check=False)
    except subprocess.TimeoutExpired:
        return {run: "importing the node modules took more than 60 s; does a module block on import?"
                for run in runs}
    answers = [line[len(_PROBE_MARK):] for line in done.stdout.splitlines() if line.startswith(_PROBE_MARK)]
    try:
        problems: dict[str, str] = json.loads(answers[-1])
        if not isinstance(problems, dict):
            raise ValueError(problems)
    except (ValueError, IndexError):
        reason = (done.stderr.strip().splitlines() or [f"exit code {done.returncode}, no error printed"])[-1]
        problems = {run: f"importing the node modules ended the interpreter before hetros could look at "
                         f"them ({reason}); does a module exit or kill its process at import?" for run in runs}
    _probed[key] = problems
    return problems


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


# how ROS 2 matches an offer to a request, per policy: the offer must be at least as strong
_RANK = {"best_effort": 0, "reliable": 1, "volatile": 0, "transient_local": 1, "automatic": 0, "manual_by_topic": 1}
_PERIODS = ("deadline", "lease_duration")  # seconds; None is infinite; the offer must be at most the request


def _offer_falls_short(policy: str, offered: object, requested: object) -> bool:
    if policy in _PERIODS:
        return requested is not None and (offered is None or float(offered) > float(requested))  # type: ignore[arg-type]
    return _RANK[str(requested)] > _RANK[str(offered)]


def _check_qos_compatibility(project: LoadedProject, publishers: dict[str, list[tuple[str, str]]],
                             subscribers: dict[str, list[tuple[str, str]]], report: CheckReport) -> None:
    """A subscriber may not request more than a publisher offers, as ROS 2 matches them:
    reliability, durability and liveliness kind by strength, deadline and lease_duration by
    period (an offered period longer than the requested one, or none, falls short)."""
    model = project.model
    for topic, subscribed in subscribers.items():
        topic_qos = model.topics.get(topic) or QoS()
        for policy in ("reliability", "durability", "deadline", "liveliness", "lease_duration"):
            default = getattr(topic_qos, policy)

            def effective(node: str, section: str, policy: str = policy, default: object = default,
                          topic: str = topic) -> object:
                spec = model.nodes[node].endpoint(section, topic)
                value = getattr(spec, policy) if spec else None
                return default if value is None else value

            def shown(value: object, policy: str = policy) -> str:
                return ("none" if value is None else f"{value:g} s") if policy in _PERIODS else str(value)

            for pub, _ in publishers.get(topic, []):
                offered = effective(pub, "publish")
                for sub, _ in subscribed:
                    requested = effective(sub, "subscribe")
                    if _offer_falls_short(policy, offered, requested):
                        report.errors.append(
                            f"{project.where('nodes', sub, 'subscribe', topic)}: incompatible QoS on "
                            f"{topic}: {sub} requests {policy} {shown(requested)} but {pub} offers "
                            f"{shown(offered)} ({project.where('nodes', pub, 'publish', topic)}); make them agree"
                        )


def _check_sources(project: LoadedProject, report: CheckReport) -> None:
    """Endpoints a node's code creates that its project entry does not declare."""
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
            declared = spec.types(section)
            for endpoint in endpoints:
                if endpoint not in declared:
                    report.errors.append(
                        f"{project.where('nodes', nname, section)}: the code of {nname} "
                        f"({found.source}) creates {section} endpoint {endpoint} that the project does "
                        f"not declare; add '{endpoint}: {endpoints[endpoint]}' here"
                    )


ROS1_BRIDGE = "hetros_ros1_bridge"


def _ros1_nodes(project: LoadedProject) -> set[str]:
    """The nodes of ``kind: ros1`` targets: ROS 1 nodes, outside the hetros channels."""
    targets = project.model.targets
    return {n for n, spec in project.model.nodes.items()
            if spec.target in targets and targets[spec.target].kind == "ros1"}


def _check_ros1_nodes(project: LoadedProject, nodes: set[str], types: TypeRegistry, report: CheckReport) -> None:
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
    ros1 = _ros1_nodes(project)
    nodes = project.model.nodes

    def endpoints(section: str, in_ros1: bool) -> set[str]:
        return {e for n, spec in nodes.items() if (n in ros1) == in_ros1 for e in getattr(spec, section)}

    return {
        "export": sorted(endpoints("publish", False) & endpoints("subscribe", True)),
        "import": sorted(endpoints("publish", True) & endpoints("subscribe", False)),
        "export_services": sorted(endpoints("services", False) & endpoints("clients", True)),
        "import_services": sorted(endpoints("services", True) & endpoints("clients", False)),
    }


def _bridged(project: LoadedProject) -> dict[str, Bridged]:
    """The ``external:`` graphs the project file names: ``ros1`` and ``ros2``."""
    external = project.model.external
    if external is None:
        return {}
    return {graph: spec for graph, spec in (("ros1", external.ros1), ("ros2", external.ros2)) if spec is not None}


# what the other graph must be able to carry, per kind of endpoint; raises MessageError if it cannot
Carries = Callable[[TypeRegistry, str, str], object]


def _ros1_carries(types: TypeRegistry, kind: str, typename: str) -> object:
    from ..transport.tcpros import Ros1ActionType, Ros1ServiceType, Ros1Type

    return {"msg": Ros1Type, "srv": Ros1ServiceType, "action": Ros1ActionType}[kind](types, typename)


def _ros2_carries(types: TypeRegistry, kind: str, typename: str) -> object:
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


def _check_bridged(project: LoadedProject, graph: str, spec: Bridged,
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



def _ros2_bridge(project: LoadedProject) -> NodePlan | None:
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
    return NodePlan(ROS2_BRIDGE, "hetros.launch._ros2_bridge:bridge", ROS2_BRIDGE, parameters,
                    publish=imports, subscribe=exports, services=import_services, clients=export_services)


def _ros1_bridge(project: LoadedProject) -> NodePlan | None:
    """The node that carries exported and imported topics across (in the launcher's process)."""
    model = project.model
    spec = model.external.ros1 if model.external is not None else None
    shared = _shared_with_ros1(project)
    if spec is not None:
        for key, listed in spec.listed().items():
            shared[key] = sorted(set(shared.get(key, ())) | set(listed))
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
    parameters = {"master": _ros1_master(project), "host": host, "export": exports, "import": imports,
                  "latch": latched, "ros1_name": f"/{model.name}_hetros",
                  "export_services": export_services, "import_services": import_services,
                  "export_actions": export_actions, "import_actions": import_actions}
    return NodePlan(ROS1_BRIDGE, "hetros.launch._ros1_bridge:bridge", ROS1_BRIDGE, parameters,
                    publish=publish, subscribe=subscribe, services=services, clients=clients,
                    actions=import_actions, action_clients=export_actions,
                    max_goals=dict.fromkeys(import_actions, 64))


def plan(project: LoadedProject, types: TypeRegistry | None = None) -> Plan:
    """Check, then compute the architecture graph. Raises CheckError with every problem."""
    types = types or registry()
    report = check(project, types)
    if report.errors:
        raise CheckError(report.errors)
    model = project.model
    process_of = {
        n: process_name(s.target, model.targets[s.target].kind) for n, s in model.nodes.items()
    }
    bridges = [b for b in (_ros1_bridge(project), _ros2_bridge(project)) if b is not None]
    speaks_ros1 = _ros1_nodes(project)
    # every hetros node's endpoints, the ROS 1 bridge's too (ROS 1 nodes' endpoints are ROS 1's):
    # (name, publish, subscribe, services, clients)
    endpoints = [(n, spec.types("publish"), spec.types("subscribe"), spec.types("services"), spec.types("clients"))
                 for n, spec in model.nodes.items() if n not in speaks_ros1]
    for bridge in bridges:
        process_of[bridge.name] = LAUNCHER
        endpoints.append((bridge.name, bridge.publish, bridge.subscribe, bridge.services, bridge.clients))
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
    fpga_of = {n: s.target for n, s in model.nodes.items() if model.targets[s.target].kind == "fpga"}
    # every target on a host: its own, else the first one named (bridges run in the first host's launcher)
    first_host = next(iter(model.hosts), "")
    host_of_target = {t: spec.host or first_host for t, spec in model.targets.items()}
    host_of = {n: host_of_target[s.target] for n, s in model.nodes.items()} | {b.name: first_host for b in bridges}

    def transport(publisher: str, subscriber: str) -> TransportKind:
        if publisher in fpga_of:
            return "hw"  # check: a topic with an endpoint on an fpga target has all of them on it
        if host_of[publisher] != host_of[subscriber]:
            return "dds"
        return "inproc" if process_of[publisher] == process_of[subscriber] else "shm"

    edges = tuple(EdgePlan(c.name, p, s, transport(p, s))
                  for c in channels.values() for p in c.publishers for s in c.subscribers)
    return Plan(
        name=model.name,
        root=str(project.root.resolve()),
        message_paths=tuple(str((project.root / m).resolve()) for m in model.messages),
        targets={n: TargetPlan(n, t.kind, tuple(t.cpus), t.clock_mhz or 100.0, t.data_width, t.part or "",
                               host_of_target[n])
                 for n, t in model.targets.items()}
        | {bridge.name: TargetPlan(bridge.name, "thread", host=first_host) for bridge in bridges},
        nodes={
            n: NodePlan(n, s.run, s.target, dict(s.parameters), s.restart, s.max_restarts, s.required,
                        s.types("publish"), s.types("subscribe"), s.types("services"), s.types("clients"),
                        {a: normalize_typename(t, "action") for a, t in s.types("actions").items()},
                        {a: normalize_typename(t, "action") for a, t in s.types("action_clients").items()},
                        s.max_goals())
            for n, s in model.nodes.items()
        } | {bridge.name: bridge for bridge in bridges},
        channels=channels,
        edges=edges,
        ros1_master=_ros1_master(project),
        ros1_host=external.ros1.host if (external := model.external) is not None and external.ros1 else "127.0.0.1",
        ros1_qos={t: q for t, q in model.topics.items()
                  if any(t in model.nodes[n].publish or t in model.nodes[n].subscribe for n in speaks_ros1)},
        hosts={n: HostPlan(n, h.address, h.ssh or "") for n, h in model.hosts.items()},
        on_peer_lost=model.on_peer_lost,
        dds_domain=model.dds_domain,
        project_hash=project_hash(project),
    )


def _ros1_master(project: LoadedProject) -> str:
    external = project.model.external
    spec = external.ros1 if external is not None else None
    if spec is None and not _ros1_nodes(project):
        return ""
    return (spec.master if spec is not None else None) or os.environ.get("ROS_MASTER_URI", "http://127.0.0.1:11311/")


def _add(channels: dict[str, ChannelPlan], name: str, typename: str, kind: str, project: LoadedProject,
         pub: str | None = None, sub: str | None = None, service: str = "") -> None:
    existing = channels.get(name)
    if existing is None:
        if kind == "topic":
            spec = project.model.topics.get(name)
            qos = spec if spec is not None else action_topic_qos(name) or QoS()
        else:
            qos = SERVICE_QOS
        existing = ChannelPlan(name, typename, kind, qos, (), (), service)  # type: ignore[arg-type]
    publishers = existing.publishers + ((pub,) if pub and pub not in existing.publishers else ())
    subscribers = existing.subscribers + ((sub,) if sub and sub not in existing.subscribers else ())
    channels[name] = ChannelPlan(existing.name, existing.type, existing.kind, existing.qos,
                                 publishers, subscribers, existing.service)


def plan_file(path: str | Path, types: TypeRegistry | None = None) -> Plan:
    return plan(load_project(path), types)


def ensure_importable(plan_: Plan) -> None:
    """Node modules resolve next to the project file first, then in the environment."""
    if plan_.root not in sys.path:
        sys.path.insert(0, plan_.root)


__all__ = ["CheckReport", "check", "ensure_importable", "load_messages", "plan", "plan_file"]
