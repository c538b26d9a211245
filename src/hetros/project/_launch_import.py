"""``hetros import roslaunch|ros2launch``: a project from ROS launch files.

ROS 1 XML (``.launch``) and ROS 2 XML or YAML (``.launch.xml``, ``.launch.yaml``) become one
project: each ``node`` a node on a process of its own, with its namespace (``ns``, ``group``,
``push-ros-namespace``), remaps, parameters (inline and from files), environment, arguments,
``required``/``respawn``; ``include``s are read in place, under their namespace and arguments;
``arg``, ``$(arg)``/``$(var)``, ``$(find pkg)``/``$(find-pkg-share pkg)``, ``$(env)``,
``$(optenv)``, ``$(dirname)`` and ``if``/``unless`` are evaluated. A node's code is found in its
package (searched under ``--package-path`` folders and beside the launch file): a ROS 1 node's
script by its ``type``, a ROS 2 node's entry point by its ``exec``; its endpoints are read from
the code as ``hetros init`` reads them. What has no counterpart (``machine``, a Python launch
file, a composable container, ...) is refused naming file:line.
"""

from __future__ import annotations

import os
import re
import shlex
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .._errors import ProjectError
from ..plan import join_namespace, resolve_name
from ._expand import flatten
from ._ros_scan import code_folders, entry_points, package_name, scan_ros_entry, scan_ros_script, unique_key

_EXECUTABLE_FOLDERS = ("scripts", "nodes", "bin", "src", "")


@dataclass
class _Element:
    tag: str
    attributes: dict[str, str]
    line: int
    children: list[_Element] = field(default_factory=list)


def _parse_xml(path: Path) -> _Element:
    root: list[_Element] = []
    stack: list[_Element] = []
    parser = xml.parsers.expat.ParserCreate()

    def start(tag: str, attributes: dict[str, str]) -> None:
        element = _Element(tag, dict(attributes), parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()
    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(path.read_bytes(), True)
    except xml.parsers.expat.ExpatError as exc:
        raise ProjectError(f"{path}:{exc.lineno}: not valid XML: {xml.parsers.expat.ErrorString(exc.code)}") from None
    except OSError as exc:
        raise ProjectError(f"cannot read launch file {path}: {exc.strerror}") from exc
    if not root or root[0].tag != "launch":
        raise ProjectError(f"{path}:1: a launch file's root element is <launch>, not <{root[0].tag if root else ''}>")
    return root[0]


def _yaml_tree(path: Path) -> _Element:
    """A ROS 2 YAML launch file as the XML form's elements (the two carry the same actions)."""
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise ProjectError(f"{path}:{mark.line + 1 if mark else 1}: not valid YAML: "
                           f"{getattr(exc, 'problem', None) or exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("launch"), list):
        raise ProjectError(f"{path}:1: a YAML launch file holds `launch:`, a list of actions")

    def convert(tag: str, body: Any) -> _Element:
        if tag == "group" and isinstance(body, list):  # a group's list form: its actions, no attributes
            return _Element(tag, {}, 0, [convert(*next(iter(item.items()))) for item in body])
        if not isinstance(body, dict):
            raise ProjectError(f"{path}: launch: {tag}: must be a mapping, not {body!r}")
        element = _Element(tag, {}, 0)
        for key, value in body.items():
            if isinstance(value, list) and key == "children":  # a group's actions
                element.children += [convert(*next(iter(item.items()))) for item in value]
            elif isinstance(value, list):
                element.children += [convert(key, item) for item in value]
            elif isinstance(value, dict):
                element.children.append(convert(key, value))
            else:
                element.attributes[key] = str(value).lower() if isinstance(value, bool) else str(value)
        return element
    return _Element("launch", {}, 0, [convert(*next(iter(item.items()))) for item in data["launch"]])


@dataclass
class _Scope:
    namespace: str = ""
    remap: dict[str, str] = field(default_factory=dict)
    env: dict[str, str] = field(default_factory=dict)
    args: dict[str, str] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)


class LaunchImporter:
    """Reads one launch file (and what it includes) into a project."""

    def __init__(self, ros2: bool, package_paths: list[Path], base: Path) -> None:
        self.ros2 = ros2
        # absolute: $(find) answers with a path that must still name the package from the project's folder
        self.package_paths = [folder.resolve() for folder in package_paths]
        self.base = base  # the folder the project file goes to: scripts and files are named relative to it
        self.project: dict[str, Any] = {"targets": {}, "nodes": {}}
        self.notes: list[str] = []
        self._packages: dict[str, list[Path]] | None = None
        # the packages whose nodes the file starts: their own msg/srv/action folders join messages:, the
        # folders ROS 2 entry points import from join python_path:
        self.used_packages: dict[Path, None] = {}
        self.imported_from: dict[Path, None] = {}
        # ROS 1: every <param>/<rosparam> outside a node by its full name; after reading, each node gets
        # those in its namespace or below under their names relative to it (``inner/b``), as rospy reads them
        self.global_params: dict[str, Any] = {}

    # -- packages --------------------------------------------------------------------------

    def find_package(self, name: str, where: str) -> list[Path]:
        """The folders holding package ``name`` (its package.xml), nearest the search paths first."""
        if self._packages is None:
            self._packages = {}
            for folder in self.package_paths:
                for xml in sorted(folder.rglob("package.xml"), key=lambda x: (len(x.parts), x)):
                    self._packages.setdefault(package_name(xml.parent), []).append(xml.parent)
        if name not in self._packages:
            searched = ", ".join(str(p) for p in self.package_paths)
            raise ProjectError(f"{where}: package {name!r} not found under {searched}; pass its folder's parent "
                               "with --package-path")
        return self._packages[name]

    # -- substitutions -----------------------------------------------------------------------

    def substitute(self, text: str, scope: _Scope, path: Path, line: int) -> str:
        def replace(match: re.Match[str]) -> str:
            words = match.group(1).split()
            kind, rest = words[0], words[1:]
            where = f"{path}:{line}"
            if kind in ("arg", "var"):
                if not rest or rest[0] not in scope.args:
                    raise ProjectError(f"{where}: $({kind} {' '.join(rest)}): no such argument; declare it with "
                                       "<arg name=... default=...>")
                return scope.args[rest[0]]
            if kind in ("find", "find-pkg-share", "find-pkg-prefix"):
                return str(self.find_package(rest[0], where)[0])
            if kind == "env":
                if rest[0] in os.environ:
                    return os.environ[rest[0]]
                if len(rest) > 1:
                    return " ".join(rest[1:])
                raise ProjectError(f"{where}: $(env {rest[0]}): {rest[0]} is not set")
            if kind == "optenv":
                return os.environ.get(rest[0], " ".join(rest[1:]))
            if kind == "dirname":
                return str(path.parent.resolve())
            if kind == "file-content":
                if not rest:
                    raise ProjectError(f"{where}: $(file-content) needs a file")
                named = Path(" ".join(rest))
                source = named if named.is_absolute() else path.parent / named
                try:
                    return source.read_text(encoding="utf-8")
                except OSError as exc:
                    raise ProjectError(f"{where}: $(file-content {named}): {exc.strerror}") from None
            if kind == "anon":
                return f"{rest[0]}_{os.getpid()}"
            raise ProjectError(f"{where}: $({kind} ...) has no counterpart in hetros; write the value out")
        return re.sub(r"\$\(([^()]*)\)", replace, text)

    def attribute(self, element: _Element, name: str, scope: _Scope, path: Path, default: str | None = None) -> str:
        value = element.attributes.get(name)
        if value is None:
            if default is None:
                raise ProjectError(f"{path}:{element.line}: <{element.tag}> needs {name}=")
            return default
        return self.substitute(value, scope, path, element.line)

    def _enabled(self, element: _Element, scope: _Scope, path: Path) -> bool:
        for key, wanted in (("if", True), ("unless", False)):
            if key in element.attributes:
                value = self.substitute(element.attributes[key], scope, path, element.line).strip().lower()
                if value not in ("true", "false", "1", "0"):
                    raise ProjectError(f"{path}:{element.line}: {key}={value!r} must be true or false")
                if (value in ("true", "1")) != wanted:
                    return False
        return True

    # -- reading -----------------------------------------------------------------------------

    def read(self, path: Path, scope: _Scope) -> None:
        if path.suffix == ".py":
            raise ProjectError(f"{path}:1: a Python launch file runs code to make its graph; hetros imports XML "
                               "and YAML launch files (write it as .launch.xml or .launch.yaml)")
        tree = _yaml_tree(path) if path.suffix in (".yaml", ".yml") else _parse_xml(path)
        self._actions(tree.children, scope, path)

    def _actions(self, elements: list[_Element], scope: _Scope, path: Path) -> None:
        for element in elements:
            if not self._enabled(element, scope, path):
                continue
            handler = getattr(self, f"_on_{element.tag.replace('-', '_')}", None)
            if handler is None:
                raise ProjectError(f"{path}:{element.line}: <{element.tag}> has no counterpart in a hetros project; "
                                   "remove it or map it by hand")
            handler(element, scope, path)

    def _on_arg(self, element: _Element, scope: _Scope, path: Path) -> None:
        name = self.attribute(element, "name", scope, path)
        if "value" in element.attributes:
            scope.args[name] = self.attribute(element, "value", scope, path)
        elif name not in scope.args:
            default = element.attributes.get("default")
            if default is None:
                raise ProjectError(f"{path}:{element.line}: argument {name!r} has no value and no default; give "
                                   "it default=")
            scope.args[name] = self.substitute(default, scope, path, element.line)

    _on_let = _on_arg

    def _on_group(self, element: _Element, scope: _Scope, path: Path) -> None:
        inner = _Scope(join_namespace(scope.namespace, self.attribute(element, "ns", scope, path, "")),
                       dict(scope.remap), dict(scope.env), dict(scope.args), dict(scope.params))
        self._actions(element.children, inner, path)

    def _on_push_ros_namespace(self, element: _Element, scope: _Scope, path: Path) -> None:
        scope.namespace = join_namespace(scope.namespace, self.attribute(element, "namespace", scope, path))

    def _on_remap(self, element: _Element, scope: _Scope, path: Path) -> None:
        scope.remap[self.attribute(element, "from", scope, path)] = self.attribute(element, "to", scope, path)

    def _on_env(self, element: _Element, scope: _Scope, path: Path) -> None:
        scope.env[self.attribute(element, "name", scope, path)] = self.attribute(element, "value", scope, path)

    _on_set_env = _on_env

    def _on_param(self, element: _Element, scope: _Scope, path: Path) -> None:
        found = self._parameters(element, scope, path)
        scope.params.update(found)
        if not self.ros2:
            for name, value in found.items():
                self.global_params[join_namespace(scope.namespace, name)] = value

    _on_rosparam = _on_param

    def share_global_params(self) -> None:
        """ROS 1's parameter server, as each node's parameters: a parameter in a node's namespace or below
        (set in a group beside or after the node) under its name relative to that namespace."""
        for node in self.project["nodes"].values():
            namespace = node.get("namespace", "").rstrip("/")
            for name, value in self.global_params.items():
                if name.startswith(f"{namespace}/"):
                    node.setdefault("parameters", {}).setdefault(name[len(namespace) + 1:], value)

    def _on_include(self, element: _Element, scope: _Scope, path: Path) -> None:
        file = Path(self.attribute(element, "file", scope, path))
        if not file.is_absolute():
            file = path.parent / file
        inner = _Scope(join_namespace(scope.namespace, self.attribute(element, "ns", scope, path, "")),
                       dict(scope.remap), dict(scope.env), {}, dict(scope.params))
        for child in element.children:
            if child.tag != "arg":
                raise ProjectError(f"{path}:{child.line}: <include> holds <arg> only, not <{child.tag}>")
            inner.args[self.attribute(child, "name", scope, path)] = self.attribute(child, "value", scope, path)
        if not file.is_file():
            raise ProjectError(f"{path}:{element.line}: included launch file {file} does not exist")
        self.read(file, inner)

    def _on_node(self, element: _Element, scope: _Scope, path: Path) -> None:
        where = f"{path}:{element.line}"
        for refused in ("machine", "launch-prefix", "launch_prefix"):
            if refused in element.attributes:
                raise ProjectError(f"{where}: <node {refused}=...> has no counterpart; a hetros node's process is "
                                   "its target (map it with targets: and hosts:)")
        package = self.attribute(element, "pkg", scope, path)
        executable = self.attribute(element, "exec" if self.ros2 else "type", scope, path)
        namespace = join_namespace(scope.namespace, self.attribute(element, "namespace" if self.ros2 else "ns", scope,
                                                                 path, ""))
        remap = dict(scope.remap)
        env = dict(scope.env)
        params = dict(scope.params)
        for child in element.children:
            if child.tag == "remap":
                remap[self.attribute(child, "from", scope, path)] = self.attribute(child, "to", scope, path)
            elif child.tag in ("param", "rosparam"):
                params.update(self._parameters(child, scope, path))
            elif child.tag in ("env", "set_env"):
                env[self.attribute(child, "name", scope, path)] = self.attribute(child, "value", scope, path)
            else:
                raise ProjectError(f"{path}:{child.line}: <node> holds <remap>, <param>, <rosparam> and <env>, not "
                                   f"<{child.tag}>")
        found = self._code(package, self.find_package(package, where), executable, where, params)
        key_name = self.attribute(element, "name", scope, path, "") or found.key
        key = unique_key(key_name, self.project["nodes"])
        node: dict[str, Any] = {"run": found.run, "target": key}
        if namespace:
            node["namespace"] = namespace
        if key_name != key or (found.ros_names and found.ros_names[0] != key_name):
            node["name"] = key_name
        for section, endpoints in found.endpoints.items():
            if endpoints:
                node[section] = dict(endpoints)
        if remap:
            node["remap"] = remap
        if params:
            node["parameters"] = params
        if env:
            node["env"] = env
        arguments = self.attribute(element, "args", scope, path, "")
        if arguments:
            node["args"] = shlex.split(arguments)
        if self.attribute(element, "required", scope, path, "false").lower() == "true":
            node["required"] = True
        if self.attribute(element, "respawn", scope, path, "false").lower() == "true":
            node["restart"] = "on-failure"
        self.project["nodes"][key] = node
        self.project["targets"][key] = {"kind": "process"}
        resolved = {resolve_name(k, namespace, key_name): resolve_name(v, namespace, key_name)
                    for k, v in remap.items()}
        topics = self.project.setdefault("topics", {})
        for topic, qos in found.qos.items():
            if not topic.startswith(("?", "~")):
                topics.setdefault(resolve_name(topic, namespace, key_name, resolved), qos)
        self.notes += [note.replace("{node}", key) for note in found.notes]

    # -- helpers -----------------------------------------------------------------------------

    def _code(self, name: str, folders: list[Path], executable: str, where: str, parameters: dict[str, Any]) -> Any:
        if self.ros2:
            targets: dict[str, str] = {}
            for package in folders:
                targets = entry_points(package)
                if executable in targets:
                    self.used_packages[package] = None
                    self.imported_from[package] = None
                    return scan_ros_entry(package, executable, targets[executable], parameters)
            raise ProjectError(f"{where}: package {name} has no entry point {executable!r} (its console_scripts: "
                               f"{', '.join(sorted(targets)) or 'none'})")
        for package in folders:
            candidates = [package / folder / executable for folder in _EXECUTABLE_FOLDERS]
            for candidate in [*candidates, *package.rglob(executable)]:
                if candidate.is_file():
                    self.used_packages[package] = None
                    return scan_ros_script(candidate, package, self.base, parameters)
        raise ProjectError(f"{where}: package {name} has no executable {executable!r} (looked in "
                           f"{', '.join(f or '.' for f in _EXECUTABLE_FOLDERS)} and below)")

    def _parameters(self, element: _Element, scope: _Scope, path: Path) -> dict[str, Any]:
        """What a <param> or <rosparam> gives: a value, or a file's (ROS 1: a mapping; ROS 2: node:
        {ros__parameters: ...})."""
        where = f"{path}:{element.line}"
        file = element.attributes.get("from") if self.ros2 else \
            element.attributes.get("file") if element.tag == "rosparam" else None
        if element.tag == "param" and not self.ros2 and ("textfile" in element.attributes or
                                                        "command" in element.attributes):
            raise ProjectError(f"{where}: <param textfile=/command=> has no counterpart; give value= or a "
                               "<rosparam file=...>")
        if file is not None:
            source = Path(self.substitute(file, scope, path, element.line))
            source = source if source.is_absolute() else path.parent / source
            try:
                data = yaml.safe_load(source.read_text(encoding="utf-8"))
            except (OSError, yaml.YAMLError) as exc:
                raise ProjectError(f"{where}: cannot read parameter file {source}: {exc}") from None
            if not isinstance(data, dict):
                return {}
            if self.ros2:
                values: dict[str, Any] = {}
                for entry in data.values():
                    if isinstance(entry, dict) and isinstance(entry.get("ros__parameters"), dict):
                        values.update(flatten(entry["ros__parameters"]))
                return values
            prefix = element.attributes.get("ns", "")
            return {f"{prefix}/{k}".lstrip("/") if prefix else k: v for k, v in flatten(data, "/").items()}
        if element.tag == "rosparam":
            body = element.attributes.get("command", "load")
            raise ProjectError(f"{where}: <rosparam command={body!r}> without a file has no counterpart; use a "
                               "parameter file")
        name = self.attribute(element, "name", scope, path)
        value = yaml.safe_load(self.attribute(element, "value", scope, path))
        kind = element.attributes.get("type")
        if kind in ("str", "string"):
            value = str(self.attribute(element, "value", scope, path))
        return {name.lstrip("/~"): value}


def import_launch(path: Path, ros2: bool, package_paths: list[Path], base: Path,
                  args: dict[str, str] | None = None) -> tuple[dict[str, Any], list[str]]:
    """The project a ROS 1 (``ros2=False``) or ROS 2 launch file describes, and notes on what the scan of
    its nodes' code could not follow."""
    importer = LaunchImporter(ros2, [*package_paths, path.parent.resolve()], base)
    importer.read(path, _Scope(args=dict(args or {})))
    importer.share_global_params()
    importer.project = {**code_folders(base, importer.imported_from, importer.used_packages), **importer.project}
    if not importer.project.get("topics"):
        importer.project.pop("topics", None)
    if not importer.project["nodes"]:
        raise ProjectError(f"{path}:1: the launch file starts no node")
    name = re.sub(r"[^A-Za-z0-9_-]", "_", path.name.split(".")[0]).lstrip("_-0123456789") or "launch"
    return {"name": name, **importer.project}, importer.notes
