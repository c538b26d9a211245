"""Importers for the two configuration formats hetros replaces.

* ROS-lite's map file: YAML entries with name, cluster, publish, publish_type,
  subscribe, subscribe_type; each cluster becomes a process target.
* ReconROS' configuration file: ``[ResourceGroup@Name]`` sections whose
  rosnode/roscpp, rosmsg, rossrvmsg, rosactionmsg, rossub, rospub, rossrvs, rossrvc,
  rosactions and rosactionc entries declare nodes and endpoints; each resource group becomes a
  process target. What has no counterpart is refused naming file:line, or named in the notes.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from dataclasses import field as dataclass_field
from pathlib import Path
from typing import Any

from .._errors import ProjectError
from .._files import load_yaml, read_text


def _as_list(value: Any) -> list[str]:
    if value is None:
        return []
    if isinstance(value, (list, tuple)):
        return [str(v) for v in value]
    return [str(value)]


def _topic(name: str) -> str:
    return name if name.startswith("/") else "/" + name


def import_roslite(path: Path, module: str = "nodes") -> dict[str, Any]:
    """A project dict from a ROS-lite .map file."""
    data = load_yaml(path, "ROS-lite map file", error=ProjectError)
    entries = data.get("nodes", data) if isinstance(data, dict) else data
    if not isinstance(entries, list):
        raise ProjectError(f"{path}: a ROS-lite map file is a list of nodes (name, cluster, publish, ...)")
    targets: dict[str, Any] = {}
    nodes: dict[str, Any] = {}
    for index, entry in enumerate(entries):
        if not isinstance(entry, dict) or "name" not in entry:
            raise ProjectError(f"{path}: entry {index} needs at least 'name' and 'cluster'")
        name = str(entry["name"])
        if "cluster" not in entry:
            raise ProjectError(f"{path}: node {name!r} (entry {index}) has no 'cluster'; assign one")
        cluster = f"cluster{entry['cluster']}"
        targets.setdefault(cluster, {"kind": "process"})
        node: dict[str, Any] = {"run": f"{module}:{name}", "target": cluster}
        for field in ("publish", "subscribe"):
            topics = _as_list(entry.get(field))
            kinds = _as_list(entry.get(f"{field}_type"))
            if len(kinds) != len(topics):
                raise ProjectError(
                    f"{path}: node {name!r}: {field} lists {len(topics)} topic(s) but {field}_type "
                    f"lists {len(kinds)} type(s); give one type per topic"
                )
            if topics:
                node[field] = {_topic(t): k for t, k in zip(topics, kinds, strict=True)}
        nodes[name] = node
    return {"name": path.stem, "targets": targets, "nodes": nodes}


_SECTION = re.compile(r"^\[(?P<kind>\w+)(?:@|\(at\))(?P<name>[^\]\(]+)(?:\((?P<start>\d+):(?P<end>\d+)\))?\]$")
# one fpga target for every hardware thread of a ReconROS build
FPGA_TARGET = "fpga"
# ReconOS's own resources (mailboxes, semaphores, ...): synchronisation between a thread's hardware
# and software halves, which hetros nodes do through topics; named in the notes, not carried over
_RECONOS_RESOURCES = {"mbox", "sem", "cond", "rq", "memory"}
_ENDPOINTS = {"rossub": ("subscribe", "msg"), "rospub": ("publish", "msg"), "rossrvs": ("services", "srv"),
              "rossrvc": ("clients", "srv"), "rossrv": ("clients", "srv"), "rosactions": ("actions", "action"),
              "rosacts": ("actions", "action"), "rosactionc": ("action_clients", "action"),
              "rosactc": ("action_clients", "action")}
_MESSAGES = {"rosmsg", "rosmg", "rossrvmsg", "rosactionmsg"}


def _fields(value: str) -> list[str]:
    """ReconROS splits a resource on commas and blanks alike (``rosmsg, sensor_msgs ,msg ,Image``)."""
    return [v.strip('"') for v in re.split(r"[, ]+", value.strip()) if v.strip('"')]


def import_reconros(path: Path, module: str = "nodes") -> tuple[dict[str, Any], list[str]]:
    """A project dict from the ROS part of a ReconROS build.cfg (Listing 1 of the paper), and notes
    naming what was not carried over (ReconOS's own resources), each with file:line.

    Each ``[ResourceGroup@…]`` becomes a process target; ``[ResourceGroup@name(0:2)]`` is three,
    ``name_0`` to ``name_2``, with ``%`` in its entries replaced by the index, as ReconROS does.
    ``rossub``/``rospub``, ``rossrvs``/``rossrvc`` and ``rosactions``/``rosactionc`` (also spelt
    ``rosacts``/``rosactc``) become endpoints. A build with hardware threads (``[ReconosThread@…]``
    with a ``HwSource``) or ``hw``-flagged ``rossub``/``rospub`` lines gets one fpga target (clock
    from the system clock, part from ``TargetPart``): nodes with hardware topics go on it, since a
    hardware topic has all its endpoints in hardware; the other nodes of hardware threads stay in
    software, one ``target:`` edit away from it. A hardware thread's nodes get ``hw:`` (its
    ``HwSource``): ``<module>_hw:<node>``, a placeholder for the Amaranth component or HLS-exported
    Verilog that ``hetros check`` refuses until written; with a ``SwSource`` too the node has both
    implementations and the target chooses, without one it goes on the fpga target. A
    ``[ROSGateway@…]`` joins its hardware topic to its software topic: in hetros they are one topic
    (the software name), and the planner adds the gateway where hardware and software meet. Message
    types may be variables (``rosmsg``…) or written inline (``sensor_msgs/Image``). What hetros has
    no counterpart for is refused with its line: a ``rosmsg`` with a sequence length (ReconROS's
    preallocated ``…__Sequence``), and any other ``ros*`` resource.
    """
    targets: dict[str, Any] = {}
    nodes: dict[str, Any] = {}
    notes: list[str] = []
    hardware_nodes: set[str] = set()
    cfg = _read_build_cfg(path, module, targets, nodes, notes, hardware_nodes)
    if not nodes:
        raise ProjectError(f"{path}: no [ResourceGroup@...] section with a rosnode/roscpp entry found")
    hardware_groups: set[str] = set()  # groups of hardware threads
    for spec in cfg.threads:
        if spec.get("HwSource") and spec.get("ResourceGroup"):
            groups_of_thread = set()
            for named in re.split(r"[, ]+", spec["ResourceGroup"].strip()):
                base = re.sub(r"\(.*\)$", "", named)
                groups_of_thread.update(cfg.ranged.get(base, [base]))
            hardware_groups.update(groups_of_thread)
            _two_implementations(path, spec, groups_of_thread, module, nodes, notes)
    for spec in cfg.gateways:
        _join_gateway(path, spec, nodes, notes)
    if hardware_nodes or hardware_groups:
        fpga: dict[str, Any] = {"kind": "fpga"}
        clock = cfg.clocks.get(cfg.general.get("SystemClock", ""), {}).get("ClockFreq", "")
        if clock.isdigit():
            fpga["clock_mhz"] = int(clock) / 1e6
        if cfg.general.get("TargetPart"):
            fpga["part"] = cfg.general["TargetPart"]
        targets[FPGA_TARGET] = fpga
        for name in sorted(hardware_nodes):
            nodes[name]["target"] = FPGA_TARGET
            nodes[name].setdefault("hw", f"{module}_hw:{name}")  # its hw-flagged endpoints exist in hardware only
        used = {spec["target"] for spec in nodes.values()} | {FPGA_TARGET}
        targets = {name: spec for name, spec in targets.items() if name in used}
    return {"name": path.stem, "targets": targets, "nodes": nodes}, notes


@dataclass
class _BuildCfg:
    """What a build.cfg says besides its resources (which go straight into targets and nodes)."""

    general: dict[str, str] = dataclass_field(default_factory=dict)
    clocks: dict[str, dict[str, str]] = dataclass_field(default_factory=dict)
    threads: list[dict[str, str]] = dataclass_field(default_factory=list)
    gateways: list[dict[str, str]] = dataclass_field(default_factory=list)
    ranged: dict[str, list[str]] = dataclass_field(default_factory=dict)  # a ranged group's name -> its expanded groups


def _read_build_cfg(path: Path, module: str, targets: dict[str, Any], nodes: dict[str, Any], notes: list[str],
                    hardware_nodes: set[str]) -> _BuildCfg:
    """Read ``path`` section by section: resources become targets and nodes as they come; the rest is kept."""
    cfg = _BuildCfg()
    # the resource groups of the current section, each with the index `%` stands for ("" without a range)
    groups: list[tuple[str, str]] = []
    section_kind = clock_name = ""
    # per group: variable -> node name / message type
    variables: dict[tuple[str, str], str] = {}
    messages: dict[tuple[str, str], str] = {}
    thread: dict[str, str] = {}
    for lineno, raw in enumerate(read_text(path, "ReconROS build.cfg", error=ProjectError).splitlines(), start=1):
        line = re.sub(r"^\d+\s+", "", raw.split("#", 1)[0].strip())
        if not line:
            continue
        if line.startswith("["):
            section = _SECTION.match(line)
            section_kind = section.group("kind") if section else line.strip("[]")
            groups = []
            if section_kind == "ROSGateway":
                thread = {"line": str(lineno), "section": line}
                cfg.gateways.append(thread)
            if section and section_kind == "ResourceGroup":
                name = section.group("name").strip()
                if section.group("start") is not None:
                    indices = range(int(section.group("start")), int(section.group("end")) + 1)
                    groups = [(f"{name}_{i}", str(i)) for i in indices]
                    cfg.ranged[name] = [group for group, _ in groups]
                else:
                    groups = [(name, "")]
            if section_kind == "ReconosThread":
                thread = {"line": str(lineno)}
                cfg.threads.append(thread)
            if section and section_kind == "Clock":
                cfg.clocks[section.group("name")] = {}
            clock_name = section.group("name") if section and section_kind == "Clock" else ""
            continue
        if "=" not in line:
            continue
        var, _, value = (p.strip() for p in line.partition("="))
        if section_kind == "General":
            cfg.general[var] = value
        elif section_kind in ("ReconosThread", "ROSGateway"):
            thread[var] = value.strip().strip('"')
        elif section_kind == "Clock" and clock_name:
            cfg.clocks[clock_name][var] = value
        else:
            for number, (group, index) in enumerate(groups):
                fields = [f.replace("%", index) for f in _fields(value)] if index else _fields(value)
                _resource(path, lineno, module, group, var, fields, targets, nodes, notes, variables, messages,
                          hardware_nodes, first=number == 0)
    return cfg


def _two_implementations(path: Path, thread: dict[str, str], groups: set[str], module: str,
                         nodes: dict[str, Any], notes: list[str]) -> None:
    """A hardware thread's nodes: ``hw:`` from its HwSource, ``run:`` kept when it has a SwSource."""
    where = f"{path}:{thread['line']}"
    named = [name for name, spec in nodes.items() if spec["target"] in {g.lower() for g in groups}]
    for name in named:
        nodes[name]["hw"] = f"{module}_hw:{name}"
    if named:
        both = "with its SwSource, both implementations: the target chooses" if thread.get("SwSource") else \
            "without a SwSource, run: is a placeholder too, so the node stays runnable in software, one target: " \
            "edit from the fpga target"
        notes.append(f"{where}: HwSource = {thread['HwSource']}: {', '.join(sorted(named))} "
                     f"{'get' if len(named) > 1 else 'gets'} hw: "
                     f"{module}_hw:<node>, a placeholder for an Amaranth component or the HLS export's Verilog "
                     f"(file.v:module) that `hetros check` refuses until written; {both}")


def _join_gateway(path: Path, gateway: dict[str, str], nodes: dict[str, Any], notes: list[str]) -> None:
    """A ReconROS gateway joins a hardware topic to a software topic: in hetros, one topic (the software one)."""
    where = f"{path}:{gateway['line']}"
    missing = [key for key in ("HWTopic", "SWTopic", "MsgType") if not gateway.get(key)]
    if missing:
        raise ProjectError(f"{where}: {gateway['section']} needs {', '.join(missing)} (a gateway joins HWTopic to "
                           "SWTopic, both of MsgType)")
    hardware, software = _topic(gateway["HWTopic"]), _topic(gateway["SWTopic"])
    parts = gateway["MsgType"].split("/")
    wanted = f"{parts[0]}/msg/{parts[-1]}"
    used = False
    for name, spec in nodes.items():
        for section in ("publish", "subscribe"):
            endpoints = spec.get(section, {})
            if hardware in endpoints:
                if endpoints[hardware] != wanted:
                    raise ProjectError(f"{where}: {gateway['section']} carries {wanted}, but node {name} "
                                       f"{section}s {hardware} as {endpoints[hardware]}; make them one type")
                endpoints[software] = endpoints.pop(hardware)
                used = True
    if not used:
        raise ProjectError(f"{where}: {gateway['section']} joins hardware topic {hardware}, which no node "
                           "publishes or subscribes; name a hardware topic of the build")
    notes.append(f"{where}: {gateway['section']} joins hardware topic {hardware} to software topic {software}: in "
                 f"hetros they are one topic, {software}; the planner adds the gateway where hardware and software "
                 "nodes meet")


def _resource(path: Path, lineno: int, module: str, group: str, var: str, fields: list[str],
              targets: dict[str, Any], nodes: dict[str, Any], notes: list[str],
              variables: dict[tuple[str, str], str], messages: dict[tuple[str, str], str],
              hardware_nodes: set[str], first: bool) -> None:
    """One ``var = kind, args...`` line of a resource group."""
    where = f"{path}:{lineno}"
    kind = fields[0] if fields else ""

    def need(count: int) -> None:
        if len(fields) < count:
            raise ProjectError(f"{where}: {kind} needs {count - 1} arguments, got {len(fields) - 1}")

    def node_of(ref: str) -> dict[str, Any]:
        if (group, ref) not in variables:
            raise ProjectError(f"{where}: {ref!r} is not a node defined earlier in this group")
        found: dict[str, Any] = nodes[variables[(group, ref)]]
        return found

    def message_of(ref: str, kind_of_type: str) -> str:
        if (group, ref) in messages:
            return messages[(group, ref)]
        parts = ref.split("/")
        if len(parts) == 2 and all(parts):  # written inline: sensor_msgs/Image
            return f"{parts[0]}/{kind_of_type}/{parts[1]}"
        if len(parts) == 3 and all(parts):
            return ref
        raise ProjectError(f"{where}: {ref!r} is neither a message defined earlier in this group "
                           "nor a type name like 'sensor_msgs/Image'")

    if kind in ("rosnode", "roscpp"):
        need(2)
        name = fields[1].lower()
        variables[(group, var)] = name
        target = group.lower()
        targets.setdefault(target, {"kind": "process"})
        nodes[name] = {"run": f"{module}:{name}", "target": target}
    elif kind in _MESSAGES:
        need(4)
        if len(fields) > 4:
            raise ProjectError(f"{where}: {kind} with a sequence length ({', '.join(fields[1:])}) is ReconROS's "
                               f"preallocated {fields[1]}/{fields[3]} sequence, which hetros does not map; drop "
                               f"the length (the topic then carries {fields[1]}/{fields[2]}/{fields[3]})")
        messages[(group, var)] = f"{fields[1]}/{fields[2]}/{fields[3]}"
    elif kind in _ENDPOINTS:
        need(4)
        section_name, type_kind = _ENDPOINTS[kind]
        node = node_of(fields[1])
        node.setdefault(section_name, {})[_topic(fields[3])] = message_of(fields[2], type_kind)
        if kind in ("rossub", "rospub") and "hw" in (f.lower() for f in fields[4:]):
            hardware_nodes.add(variables[(group, fields[1])])
    elif kind.startswith("ros"):
        raise ProjectError(f"{where}: {kind} is a ReconROS resource hetros does not map (it maps "
                           f"{', '.join(sorted({'rosnode', *_MESSAGES, *_ENDPOINTS}))})")
    elif kind in _RECONOS_RESOURCES and first:
        notes.append(f"{where}: {var} = {kind} is ReconOS's own {kind} resource between a thread's hardware and "
                     "software halves; hetros nodes talk through topics, so it is not carried over")
