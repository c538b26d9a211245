"""The launch conveniences of a project file, expanded away: substitutions, groups, instances, includes,
namespaces, remaps and parameter files.

What the planner and the checks see is a flat project: every node under ``nodes:`` with its final
name, target and parameters, and every endpoint under its fully qualified, remapped name. Each node
keeps its namespace, ROS name and remaps, since its code still asks for names (``'chatter'``) that
the runtime resolves the same way (:func:`resolve_name`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._errors import ProjectError
from .._files import load_yaml, parse_yaml
from ..plan import join_namespace, resolve_name

# $(arg name), $(env NAME), $(env NAME default), $(dirname): ROS launch's substitutions
_SUBSTITUTION = re.compile(r"\$\((arg|env|dirname)(?:\s+([^\s)]+))?(?:\s+([^)]*))?\)")
MAX_INCLUDE_DEPTH = 16
_SECTIONS = ("publish", "subscribe", "services", "clients", "actions", "action_clients")


def substitute(text: str, path: Path, args: Mapping[str, object]) -> str:
    """``text`` with its ``$(...)`` substitutions replaced; an unknown one names file:line."""

    def replace(match: re.Match[str]) -> str:
        kind, name, default = match.group(1), match.group(2), match.group(3)
        line = text.count("\n", 0, match.start()) + 1
        if kind == "dirname":
            return str(path.parent.resolve())
        if name is None:
            raise ProjectError(f"{path}:{line}: {match.group(0)} names nothing; write $({kind} NAME)")
        if kind == "env":
            value = os.environ.get(name, default)
            if value is None:
                raise ProjectError(f"{path}:{line}: $(env {name}): {name} is not set; set it, or give a default "
                                   f"as $(env {name} default)")
            return value
        if name not in args:
            raise ProjectError(f"{path}:{line}: $(arg {name}): no such argument; declare it under args: (with a "
                               "default) or pass it in the include's args:")
        given = args[name]
        return str(given).lower() if isinstance(given, bool) else str(given)
    return _SUBSTITUTION.sub(replace, text)


def declared_args(text: str) -> dict[str, object]:
    """The ``args:`` defaults of a project file's text (read before its substitutions are made)."""
    try:
        data = parse_yaml(_SUBSTITUTION.sub("0", text), "project file", error=ProjectError)
    except ProjectError:
        return {}  # the real parse reports it, with its line
    found = data.get("args") if isinstance(data, dict) else None
    return dict(found) if isinstance(found, dict) else {}


def parameters_from_files(files: list[Path], fq_name: str) -> dict[str, Any]:
    """What ROS 2 parameter files give the node ``fq_name`` (``/ns/node``): entries under ``/**``, the node's
    name or its fully qualified name, in file order; nested mappings flatten to dotted names."""
    found: dict[str, Any] = {}
    short = fq_name.rsplit("/", 1)[-1]
    for file in files:
        data = load_yaml(file, "parameter file", error=ProjectError)
        if not isinstance(data, dict):
            raise ProjectError(f"{file}:1: a ROS 2 parameter file maps node names to {{ros__parameters: ...}}")
        for key, entry in data.items():
            if _matches(str(key), fq_name, short):
                if not isinstance(entry, dict) or not isinstance(entry.get("ros__parameters"), dict):
                    raise ProjectError(f"{file}: {key}: must hold ros__parameters: a mapping of parameter values")
                found.update(flatten(entry["ros__parameters"]))
    return found


def _matches(key: str, fq_name: str, short: str) -> bool:
    if key in ("/**", "**", short, fq_name, fq_name.lstrip("/")):
        return True
    if "*" in key:  # /**/node, /ns/*: ROS 2's wildcards
        pattern = re.escape("/" + key.lstrip("/")).replace(r"/\*\*", "(/[^/]+)*").replace(r"\*", "[^/]+")
        return re.fullmatch(pattern, fq_name) is not None
    return False


def flatten(values: Mapping[str, Any], joiner: str = ".", prefix: str = "") -> dict[str, Any]:
    """Nested parameter mappings as flat names (``gains: {p: 2}`` -> ``gains.p``; ROS 1 joins with ``/``)."""
    flat: dict[str, Any] = {}
    for key, value in values.items():
        if isinstance(value, Mapping):
            flat.update(flatten(value, joiner, f"{prefix}{key}{joiner}"))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


@dataclass
class Expanded:
    """A flat project's parts, and where each expanded node came from."""

    nodes: dict[str, dict[str, Any]] = field(default_factory=dict)
    targets: dict[str, Any] = field(default_factory=dict)
    topics: dict[str, Any] = field(default_factory=dict)
    # ROS 1's parameter server: every file's, by absolute name (a later file's value wins)
    parameters: dict[str, Any] = field(default_factory=dict)
    messages: list[str] = field(default_factory=list)
    # python_path: folders of every file, absolute (an included file's are relative to it)
    python_path: list[str] = field(default_factory=list)
    # expanded YAML path -> the path of what it came from, for error messages
    aliases: dict[tuple[str, ...], tuple[str, ...]] = field(default_factory=dict)
    # node -> the folder its run: is relative to (an included file's)
    roots: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class _Scope:
    """What a node inherits from the groups and includes around it."""

    namespace: str = ""
    remap: tuple[tuple[str, str], ...] = ()
    env: tuple[tuple[str, str], ...] = ()
    parameters: tuple[tuple[str, Any], ...] = ()
    parameter_files: tuple[Path, ...] = ()
    prefix: str = ""
    folder: Path = Path()
    targets: tuple[tuple[str, str], ...] = ()
    origin: tuple[str, ...] = ()


def expand(data: dict[str, Any], path: Path, load: Callable[[Path, dict[str, object], int], dict[str, Any]],
           depth: int = 0) -> Expanded:
    """Flatten the validated-shape ``data`` of the project file ``path`` (``load`` reads an included one)."""
    out = Expanded()
    _expand_into(out, data, _Scope(folder=path.parent), path, load, depth)
    return out


def _expand_into(out: Expanded, data: dict[str, Any], scope: _Scope, path: Path,
                 load: Callable[[Path, dict[str, object], int], dict[str, Any]], depth: int) -> None:
    targets = dict(scope.targets)
    for name, target in (data.get("targets") or {}).items():
        if name not in targets:
            out.targets[_prefixed(scope.prefix, name, "_")] = target
    for topic, qos in (data.get("topics") or {}).items():
        out.topics[resolve_name(topic, scope.namespace, "")] = qos
    out.parameters.update(data.get("parameters") or {})
    known = {(scope.folder / m).resolve() for m in out.messages}
    for folder in data.get("messages") or []:
        if (scope.folder / folder).resolve() not in known:
            out.messages.append(str((scope.folder / folder).resolve()) if scope.prefix else folder)
    for folder in data.get("python_path") or []:
        if (absolute := str((scope.folder / folder).resolve())) not in out.python_path:
            out.python_path.append(absolute)
    for key, spec in (data.get("nodes") or {}).items():
        _node(out, key, spec, scope, ("nodes", key))
    for group_name, group in (data.get("groups") or {}).items():
        inner = _Scope(join_namespace(scope.namespace, group.get("namespace", "")),
                       scope.remap + tuple(group.get("remap", {}).items()),
                       scope.env + tuple(group.get("env", {}).items()),
                       scope.parameters + tuple(group.get("parameters", {}).items()),
                       scope.parameter_files + tuple(scope.folder / f for f in group.get("parameter_files", [])),
                       scope.prefix, scope.folder, scope.targets, scope.origin)
        for key, spec in (group.get("nodes") or {}).items():
            _node(out, key, spec, inner, ("groups", group_name, "nodes", key))
    for include_name, include in (data.get("include") or {}).items():
        where = ("include", include_name)
        file = (scope.folder / include["file"]).resolve()
        if depth >= MAX_INCLUDE_DEPTH:
            raise ProjectError(f"{path}: include.{include_name}: includes nest more than {MAX_INCLUDE_DEPTH} deep; "
                               "does a file include itself?")
        included = load(file, dict(include.get("args", {})), depth + 1)
        mapped = tuple((theirs, targets.get(ours, ours)) for theirs, ours in include.get("targets", {}).items())
        for _theirs, ours in mapped:
            if ours not in (data.get("targets") or {}) and ours not in out.targets:
                raise ProjectError(f"{path}: include.{include_name}.targets: {ours!r} is not a target of this "
                                   "project; map onto one under targets:")
        inner = _Scope(join_namespace(scope.namespace, include.get("namespace", "")), scope.remap, scope.env,
                       scope.parameters, scope.parameter_files, _prefixed(scope.prefix, include_name, "_"),
                       file.parent, mapped, scope.origin or where)
        _expand_into(out, included, inner, file, load, depth + 1)


def _prefixed(prefix: str, name: str, joiner: str) -> str:
    return f"{prefix}{joiner}{name}" if prefix else name


def _node(out: Expanded, key: str, spec: dict[str, Any], scope: _Scope, origin: tuple[str, ...]) -> None:
    instances = spec.get("instances") or {}
    base = {k: v for k, v in spec.items() if k != "instances"}
    if not instances:
        _one(out, key, base, scope, origin)
        return
    for instance_name, instance in instances.items():
        merged = dict(base)
        for field_name in ("namespace", "name", "target", "args"):
            if instance.get(field_name) is not None:
                merged[field_name] = instance[field_name]
        for field_name in ("remap", "parameters", "env"):
            merged[field_name] = {**base.get(field_name, {}), **instance.get(field_name, {})}
        merged["parameter_files"] = [*base.get("parameter_files", []), *instance.get("parameter_files", [])]
        _one(out, instance_name, merged, scope, (*origin, "instances", instance_name))


def _one(out: Expanded, key: str, spec: dict[str, Any], scope: _Scope, origin: tuple[str, ...]) -> None:
    name = _prefixed(scope.prefix, key, "_")
    if name in out.nodes:
        raise ProjectError(f"node {name!r} is defined twice (nodes, groups, instances and includes share one "
                           "set of names); rename one")
    namespace = join_namespace(scope.namespace, spec.get("namespace", ""))
    remap_given = {**dict(scope.remap), **spec.get("remap", {})}
    # an included node keeps its own name in ROS (its key takes the include's prefix: it must be unique here)
    ros_name = remap_given.pop("__node", None) or spec.get("name") or (key if scope.prefix else None)
    namespace = join_namespace(namespace, remap_given.pop("__ns", "")) if "__ns" in remap_given else namespace
    own_name = ros_name or key
    remap = {resolve_name(k, namespace, own_name): resolve_name(v, namespace, own_name)
             for k, v in remap_given.items()}
    node = dict(spec)
    node.update(namespace=namespace, name=ros_name, remap=remap, env={**dict(scope.env), **spec.get("env", {})})
    target = spec.get("target", "")
    node["target"] = dict(scope.targets).get(target, _prefixed(scope.prefix, target, "_"))
    files = [*scope.parameter_files, *(scope.folder / f for f in spec.get("parameter_files", []))]
    fq_name = f"{namespace}/{own_name}"
    node["parameters"] = {**dict(scope.parameters), **parameters_from_files(files, fq_name),
                          **spec.get("parameters", {})}
    node["parameter_files"] = []
    run = str(spec.get("run", ""))
    if scope.prefix and ":" not in run and run:
        node["run"] = str((scope.folder / run).resolve())  # a script's path, relative to its own file
    for section in _SECTIONS:
        table = spec.get(section) or {}
        node[section] = {resolve_name(endpoint, namespace, own_name, remap): value
                         for endpoint, value in table.items()}
        for endpoint in table:
            out.aliases[("nodes", name, section, resolve_name(endpoint, namespace, own_name, remap))] = \
                (*(scope.origin or origin), section, endpoint) if not scope.origin else scope.origin
    out.nodes[name] = node
    out.aliases[("nodes", name)] = scope.origin or origin
    if scope.prefix:
        out.roots[name] = str(scope.folder)
