"""Importers for the two configuration formats hetros replaces.

* ROS-lite's map file: YAML entries with name, cluster, publish, publish_type,
  subscribe, subscribe_type; each cluster becomes a process target.
* ReconROS' configuration file: ``[ResourceGroup@Name]`` sections whose
  rosnode/roscpp, rosmsg, rossrvmsg, rosactionmsg, rossub, rospub, rossrvs, rossrv,
  rosactions and rosactionc entries declare nodes and endpoints; each resource group becomes a process target.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from .._errors import ProjectError


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
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise ProjectError(f"{path}: not a valid ROS-lite map file (YAML): {exc}") from exc
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


_SECTION = re.compile(r"^\[(?P<kind>\w+)(?:@|\(at\))(?P<name>[^\]]+)\]$")
# one fpga target for every hardware thread of a ReconROS build
FPGA_TARGET = "fpga"


def _fields(value: str) -> list[str]:
    return [v.strip().strip('"') for v in value.split(",")]


def import_reconros(path: Path, module: str = "nodes") -> dict[str, Any]:
    """A project dict from the ROS part of a ReconROS build.cfg (Listing 1 of the paper).

    Each ``[ResourceGroup@…]`` becomes a process target. A build with hardware threads
    (``[ReconosThread@…]`` with a ``HwSource``) or ``hw``-flagged ``rossub``/``rospub`` lines gets
    one fpga target (clock from the system clock, part from ``TargetPart``): nodes with hardware
    topics go on it, since a hardware topic has all its endpoints in hardware; the other nodes
    of hardware threads stay in software, runnable, one ``target:`` edit away from it. Message
    types may be variables (``rosmsg``…) or written inline (``sensor_msgs/Image``).
    """
    targets: dict[str, Any] = {}
    nodes: dict[str, Any] = {}
    group = ""
    section_kind = ""
    variables: dict[str, str] = {}
    messages: dict[str, str] = {}
    group_of: dict[str, str] = {}
    hardware_nodes: set[str] = set()
    hardware_groups: set[str] = set()  # groups of hardware threads
    thread: dict[str, str] = {}
    general: dict[str, str] = {}
    clocks: dict[str, dict[str, str]] = {}
    threads: list[dict[str, str]] = []
    clock_name = ""
    for lineno, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        line = re.sub(r"^\d+\s+", "", raw.split("#", 1)[0].strip())
        if not line:
            continue
        section = _SECTION.match(line)
        if section or line.startswith("["):
            section_kind = section.group("kind") if section else line.strip("[]")
            group = section.group("name") if section and section_kind == "ResourceGroup" else ""
            if section_kind == "ReconosThread":
                thread = {}
                threads.append(thread)
            if section and section_kind == "Clock":
                clocks[section.group("name")] = {}
            clock_name = section.group("name") if section and section_kind == "Clock" else ""
            continue
        if "=" not in line:
            continue
        var, _, value = (p.strip() for p in line.partition("="))
        if section_kind == "General":
            general[var] = value
            continue
        if section_kind == "ReconosThread":
            thread[var] = value
            continue
        if section_kind == "Clock" and clock_name:
            clocks[clock_name][var] = value
            continue
        if not group:
            continue
        fields = _fields(value)
        kind = fields[0]

        def need(count: int) -> None:
            if len(fields) < count:
                raise ProjectError(f"{path}:{lineno}: {kind} needs {count - 1} arguments, got {len(fields) - 1}")

        def node_of(ref: str) -> dict[str, Any]:
            if ref not in variables:
                raise ProjectError(f"{path}:{lineno}: {ref!r} is not a node defined earlier in this group")
            found: dict[str, Any] = nodes[variables[ref]]
            return found

        def message_of(ref: str, kind_of_type: str = "msg") -> str:
            if ref in messages:
                return messages[ref]
            parts = ref.split("/")
            if len(parts) == 2 and all(parts):  # written inline: sensor_msgs/Image
                return f"{parts[0]}/{kind_of_type}/{parts[1]}"
            if len(parts) == 3 and all(parts):
                return ref
            raise ProjectError(f"{path}:{lineno}: {ref!r} is neither a message defined earlier in this group "
                               "nor a type name like 'sensor_msgs/Image'")

        if kind in ("rosnode", "roscpp"):
            need(2)
            name = fields[1].lower()
            variables[var] = name
            target = group.lower()
            targets.setdefault(target, {"kind": "process"})
            nodes[name] = {"run": f"{module}:{name}", "target": target}
            group_of[name] = group
        elif kind in ("rosmsg", "rosmg", "rossrvmsg", "rosactionmsg"):
            need(4)
            messages[var] = f"{fields[1]}/{fields[2]}/{fields[3]}"
        elif kind in ("rossub", "rospub"):
            need(4)
            section_name = "subscribe" if kind == "rossub" else "publish"
            node_of(fields[1]).setdefault(section_name, {})[_topic(fields[3])] = message_of(fields[2])
            if "hw" in (f.lower() for f in fields[4:]):
                hardware_nodes.add(variables[fields[1]])
        elif kind in ("rossrvs", "rossrv"):
            need(4)
            section_name = "services" if kind == "rossrvs" else "clients"
            node_of(fields[1]).setdefault(section_name, {})[_topic(fields[3])] = message_of(fields[2], "srv")
        elif kind in ("rosactions", "rosactionc"):
            need(4)
            section_name = "actions" if kind == "rosactions" else "action_clients"
            node_of(fields[1]).setdefault(section_name, {})[_topic(fields[3])] = message_of(fields[2], "action")
        else:
            continue
    if not nodes:
        raise ProjectError(f"{path}: no [ResourceGroup@...] section with a rosnode/roscpp entry found")
    for spec in threads:
        if spec.get("HwSource") and spec.get("ResourceGroup"):
            hardware_groups.update(g.strip() for g in spec["ResourceGroup"].split(","))
    if hardware_nodes or hardware_groups:
        fpga: dict[str, Any] = {"kind": "fpga"}
        clock = clocks.get(general.get("SystemClock", ""), {}).get("ClockFreq", "")
        if clock.isdigit():
            fpga["clock_mhz"] = int(clock) / 1e6
        if general.get("TargetPart"):
            fpga["part"] = general["TargetPart"]
        targets[FPGA_TARGET] = fpga
        for name in hardware_nodes:
            nodes[name]["target"] = FPGA_TARGET
        used = {spec["target"] for spec in nodes.values()} | {FPGA_TARGET}
        targets = {name: spec for name, spec in targets.items() if name in used}
    return {"name": path.stem, "targets": targets, "nodes": nodes}
