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

import json
import os
import re
import shlex
import subprocess
import sys
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._errors import ProjectError
from .._files import DEPTH_LIMIT, load_yaml, parse_yaml, read_bytes, read_text
from ..plan import LIFECYCLE_TRANSITIONS, join_namespace, resolve_name
from ._expand import flatten, parameters_from_files
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
        if len(stack) >= DEPTH_LIMIT:
            raise ProjectError(f"{path}:{parser.CurrentLineNumber}: elements nested more than {DEPTH_LIMIT} deep; "
                               "no launch file is")
        element = _Element(tag, dict(attributes), parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()
    parser.StartElementHandler = start
    parser.EndElementHandler = end
    data = read_bytes(path, "launch file", error=ProjectError)
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as exc:
        raise ProjectError(f"{path}:{exc.lineno}: not valid XML: {xml.parsers.expat.ErrorString(exc.code)}") from None
    if not root or root[0].tag != "launch":
        raise ProjectError(f"{path}:1: a launch file's root element is <launch>, not <{root[0].tag if root else ''}>")
    return root[0]


def _yaml_tree(path: Path) -> _Element:
    """A ROS 2 YAML launch file as the XML form's elements (the two carry the same actions)."""
    data = load_yaml(path, "launch file", error=ProjectError)
    if not isinstance(data, dict) or not isinstance(data.get("launch"), list):
        raise ProjectError(f"{path}:1: a YAML launch file holds `launch:`, a list of actions")

    def action(item: Any) -> _Element:
        """One list entry: a mapping of one action name to its body."""
        if not isinstance(item, dict) or len(item) != 1:
            raise ProjectError(f"{path}: launch: each action is a mapping of its name to its body "
                               f"(- node: {{...}}), not {str(item)[:60]!r}")
        tag, body = next(iter(item.items()))
        return convert(str(tag), body)

    def convert(tag: str, body: Any) -> _Element:
        if tag == "group" and isinstance(body, list):  # a group's list form: its actions, no attributes
            return _Element(tag, {}, 0, [action(item) for item in body])
        if not isinstance(body, dict):
            raise ProjectError(f"{path}: launch: {tag}: must be a mapping, not {body!r}")
        element = _Element(tag, {}, 0)
        for key, value in body.items():
            if isinstance(value, list) and key == "children":  # a group's actions
                element.children += [action(item) for item in value]
            elif isinstance(value, list):
                element.children += [convert(key, item) for item in value]
            elif isinstance(value, dict):
                element.children.append(convert(key, value))
            else:
                element.attributes[str(key)] = str(value).lower() if isinstance(value, bool) else str(value)
        return element
    return _Element("launch", {}, 0, [action(item) for item in data["launch"]])


@dataclass
class NodeRequest:
    """One node a launch file starts, in whichever form it wrote it, before its code is found."""

    where: str
    package: str
    executable: str
    name: str = ""
    namespace: str = ""
    remap: dict[str, str] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)
    env: dict[str, str] = field(default_factory=dict)
    args: list[str] = field(default_factory=list)
    required: bool = False
    respawn: bool = False
    lifecycle: str | None = None  # a managed node's state once the launch has started it
    plugin: str = ""  # a component's plugin name (``executable`` is then empty)
    container: str = ""  # the container a component is loaded into: the process target it shares

    @property
    def full_name(self) -> str:
        return f"{self.namespace.rstrip('/')}/{self.name}"


@dataclass
class _Scope:
    namespace: str = ""
    remap: dict[str, str] = field(default_factory=dict)
    env: dict[str, str] = field(default_factory=dict)
    args: dict[str, str] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)


# what $(file-content) takes in: a URDF or a small config, not a disk image
FILE_CONTENT_LIMIT = 4 << 20


class LaunchNotes(list[str]):
    """The notes of an import, and the widest mode its project file may have: no wider than the files
    whose text ``$(file-content)`` copied into it (a key readable by you alone stays so)."""

    file_mode = 0o666


def _value(text: str, where: str) -> Any:
    """A parameter's value written in a launch file or on a node's command line, read as YAML."""
    return parse_yaml(text, f"{where}: the value {text[:40]!r}", error=ProjectError)


# a robot's launch tree includes a few dozen files, a few levels deep
MAX_INCLUDE_DEPTH = 32
MAX_INCLUDED_FILES = 1000


class LaunchImporter:
    """Reads one launch file (and what it includes) into a project."""

    def __init__(self, ros2: bool, package_paths: list[Path], base: Path) -> None:
        self.ros2 = ros2
        # absolute: $(find) answers with a path that must still name the package from the project's folder
        self.package_paths = [folder.resolve() for folder in package_paths]
        self.base = base  # the folder the project file goes to: scripts and files are named relative to it
        self.project: dict[str, Any] = {"targets": {}, "nodes": {}}
        self.notes = LaunchNotes()
        self._packages: dict[str, list[Path]] | None = None
        # the packages whose nodes the file starts: their own msg/srv/action folders join messages:, the
        # folders ROS 2 entry points import from join python_path:
        self.used_packages: dict[Path, None] = {}
        self.imported_from: dict[Path, None] = {}
        self._including: list[Path] = []  # the files being read, outermost first (an include loop shows here)
        self._files_read = 0

    # -- packages --------------------------------------------------------------------------

    def find_package(self, name: str, where: str) -> list[Path]:
        """The folders holding package ``name`` (its package.xml), nearest the search paths first."""
        packages = self._package_index()
        if name not in packages:
            searched = ", ".join(str(p) for p in self.package_paths)
            raise ProjectError(f"{where}: package {name!r} not found under {searched}; pass its folder's parent "
                               "with --package-path")
        return packages[name]

    def _package_index(self) -> dict[str, list[Path]]:
        if self._packages is None:
            self._packages = {}
            for folder in self.package_paths:
                for xml in sorted(folder.rglob("package.xml"), key=lambda x: (len(x.parts), x)):
                    self._packages.setdefault(package_name(xml.parent), []).append(xml.parent)
        return self._packages

    # -- substitutions -----------------------------------------------------------------------

    def _file_content(self, source: Path, where: str) -> str:
        """``$(file-content FILE)``: the text, capped; a file outside the launch file's package is read but
        named in the notes, and the project's file mode narrows to the file's."""
        text = read_text(source, f"{where}: $(file-content)", limit=FILE_CONTENT_LIMIT, error=ProjectError)
        reading = self._including[-1]
        if not source.resolve().is_relative_to(_package_of(reading) or reading.parent):
            self.notes.append(f"{where}: $(file-content {source}) read a file outside the launch file's package; "
                              "its text is now in the project file")
        self.notes.file_mode &= os.stat(source).st_mode & 0o777
        return text

    def substitute(self, text: str, scope: _Scope, path: Path, line: int) -> str:
        def replace(match: re.Match[str]) -> str:
            words = match.group(1).split()
            where = f"{path}:{line}"
            if not words:
                raise ProjectError(f"{where}: an empty $(); write a substitution ($(arg name), ...) or the value")
            kind, rest = words[0], words[1:]
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
                return self._file_content(source, where)
            if kind == "anon":
                return f"{rest[0]}_{os.getpid()}"
            raise ProjectError(f"{where}: $({kind} ...) has no counterpart in hetros; write the value out")
        done = re.sub(r"\$\(([^()]*)\)", replace, text)
        if "$(" in done:  # what the pattern cannot take apart ($(eval ...) with parentheses inside) is not kept
            left = done[done.index("$("):][:60]
            raise ProjectError(f"{path}:{line}: {left!r}: hetros evaluates $(arg), $(env), $(optenv), $(find), "
                               "$(dirname), $(file-content) and $(anon) only; write the value out")
        return done

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
        """One launch file, and through it what it includes: an include loop, includes nested deeper than
        ``MAX_INCLUDE_DEPTH`` or more than ``MAX_INCLUDED_FILES`` files in all are refused by name."""
        resolved = path.resolve()
        if resolved in self._including:
            chain = " -> ".join(str(p) for p in (*self._including[self._including.index(resolved):], resolved))
            raise ProjectError(f"{path}:1: an include loop: {chain}; break it")
        if len(self._including) >= MAX_INCLUDE_DEPTH:
            raise ProjectError(f"{path}:1: includes nested more than {MAX_INCLUDE_DEPTH} deep; no launch tree is")
        self._files_read += 1
        if self._files_read > MAX_INCLUDED_FILES:
            raise ProjectError(f"{path}:1: more than {MAX_INCLUDED_FILES} launch files read for one import; an "
                               "include fans out without end")
        self._including.append(resolved)
        try:
            if path.suffix == ".py":
                if not self.ros2:
                    raise ProjectError(f"{path}:1: a Python launch file is ROS 2's; import it with `hetros import "
                                       "ros2launch`")
                self._python(path, scope)
                return
            tree = _yaml_tree(path) if path.suffix in (".yaml", ".yml") else _parse_xml(path)
            self._actions(tree.children, scope, path)
        finally:
            self._including.pop()

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
        """ROS 2: a parameter of every node after it in its scope. ROS 1: a parameter of the parameter
        server (the project's ``parameters:``), by its full name, which every node reads by it."""
        found = self._parameters(element, scope, path, keep_absolute=True)
        if self.ros2:
            scope.params.update(found)
            return
        for name, value in found.items():
            full = name if name.startswith("/") else join_namespace(scope.namespace, name)
            self.project.setdefault("parameters", {})[full] = value

    _on_rosparam = _on_param

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
        if not _is_file(file):
            raise ProjectError(f"{path}:{element.line}: included launch file {file} does not exist")
        self.read(file, inner)

    def _on_node(self, element: _Element, scope: _Scope, path: Path) -> None:
        where = f"{path}:{element.line}"
        for refused in ("machine", "launch-prefix", "launch_prefix"):
            if refused in element.attributes:
                raise ProjectError(f"{where}: <node {refused}=...> has no counterpart; a hetros node's process is "
                                   "its target (map it with targets: and hosts:)")
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
        self.add_node(NodeRequest(
            where=where, package=self.attribute(element, "pkg", scope, path),
            executable=self.attribute(element, "exec" if self.ros2 else "type", scope, path),
            name=self.attribute(element, "name", scope, path, ""), namespace=namespace, remap=remap, params=params,
            env=env, args=shlex.split(self.attribute(element, "args", scope, path, "")),
            required=self.attribute(element, "required", scope, path, "false").lower() == "true",
            respawn=self.attribute(element, "respawn", scope, path, "false").lower() == "true"))

    def add_node(self, request: NodeRequest) -> str:
        """One node of the launch (any of its forms) into the project: its code found in its package, its
        command line's ROS arguments applied as ROS applies them; its key."""
        args = self._ros_arguments(request)
        found = self._code(request.package, self.find_package(request.package, request.where),
                           request.plugin or request.executable, request.where, request.params,
                           "rclpy_components" if request.plugin else "console_scripts")
        code_name = found.ros_names[0] if len(set(found.ros_names)) == 1 else ""
        key_name = request.name or code_name or found.key
        key = unique_key(key_name, self.project["nodes"])
        target = unique_key(request.container.strip("/").replace("/", "_"), {}) if request.container else key
        node: dict[str, Any] = {"run": found.run, "target": target}
        namespace = request.namespace
        if namespace:
            node["namespace"] = namespace
        # the launch's name stands over the code's (an anonymous one's too, as roslaunch's __name:= does);
        # without one the node keeps its code's, as in ROS
        if request.name:
            node["name"] = request.name
        elif code_name and code_name != key:
            node["name"] = code_name
        for section, endpoints in found.endpoints.items():
            if endpoints:
                node[section] = dict(endpoints)
        for option, value in (("remap", request.remap), ("parameters", request.params), ("env", request.env),
                              ("args", args)):
            if value:
                node[option] = value
        if request.required:
            node["required"] = True
        if request.respawn:
            node["restart"] = "on-failure"
        if request.lifecycle is not None or found.managed:
            node["lifecycle"] = request.lifecycle or "unconfigured"
        self.project["nodes"][key] = node
        self.project["targets"][target] = {"kind": "process"}
        resolved = {resolve_name(k, namespace, key_name): resolve_name(v, namespace, key_name)
                    for k, v in request.remap.items()}
        topics = self.project.setdefault("topics", {})
        for topic, qos in found.qos.items():
            if not topic.startswith(("?", "~")):
                topics.setdefault(resolve_name(topic, namespace, key_name, resolved), qos)
        self.notes += [note.replace("{node}", key) for note in found.notes]
        return key

    def _ros_arguments(self, request: NodeRequest) -> list[str]:
        """``request.args`` less what ROS reads from a node's command line, applied to the request: ROS 1's
        ``from:=to`` remaps, ``_param:=value``, ``__name:=`` and ``__ns:=``; ROS 2's ``--ros-args`` section
        (``-r``/``--remap``, ``-p``/``--param``, ``--params-file``, and the same ``__node:=``/``__ns:=``)."""
        kept: list[str] = []
        words = iter(request.args)
        inside = False
        for word in words:
            if self.ros2 and word == "--ros-args":
                inside = True
            elif inside and word == "--":
                inside = False
            elif inside and word in ("-r", "--remap", "-p", "--param", "--params-file", "-e", "--enclave",
                                     "--log-level", "--log-config-file"):
                value = next(words, None)
                if value is None:
                    raise ProjectError(f"{request.where}: {word} needs a value in the node's --ros-args")
                if word in ("-r", "--remap"):
                    self._name_assignment(value, request, remap_only=True)
                elif word in ("-p", "--param"):
                    name, _, text = value.partition(":=")
                    request.params[name] = _value(text, request.where) if text else text
                elif word == "--params-file":
                    request.params.update(ros2_parameter_file(Path(value), request.full_name, request.where))
            elif inside:
                continue  # the flags ROS reads without a value (--disable-rosout-logs, ...)
            elif ":=" in word and (not self.ros2 or word.startswith("__")):
                self._name_assignment(word, request, remap_only=False)
            else:
                kept.append(word)
        return kept

    def _name_assignment(self, word: str, request: NodeRequest, remap_only: bool) -> None:
        name, _, value = word.partition(":=")
        if ":" in name and not name.startswith("/"):
            name = name.split(":", 1)[1]  # ROS 2's node-qualified remap (talker:chatter:=x) names this node
        if name in ("__node", "__name") and not remap_only:
            request.name = value
        elif name == "__ns" and not remap_only:
            request.namespace = join_namespace("", value)
        elif name.startswith("_") and not name.startswith("__") and not self.ros2 and not remap_only:
            request.params[name[1:]] = _value(value, request.where) if value else value
        elif name.startswith("__"):
            raise ProjectError(f"{request.where}: the argument {word!r} has no counterpart in hetros")
        else:
            request.remap[name] = value

    # -- Python launch files ------------------------------------------------------------------

    def _python(self, path: Path, scope: _Scope) -> None:
        """The file's ``generate_launch_description()`` run in an interpreter of its own against hetros's
        ``launch`` and ``launch_ros`` (:mod:`hetros.compat.launch_eval`), and what it records read here."""
        packages = {name: str(folders[0]) for name, folders in self._package_index().items()}
        request = {"file": str(path.resolve()), "args": scope.args, "packages": packages, "namespace": scope.namespace,
                   "remap": list(scope.remap.items()), "params": list(scope.params.items())}
        try:
            done = subprocess.run([sys.executable, "-m", "hetros.compat.launch_eval"], input=json.dumps(request),
                                  capture_output=True, text=True, timeout=_PYTHON_LAUNCH_SECONDS, check=False,
                                  cwd=path.parent)
        except subprocess.TimeoutExpired:
            raise ProjectError(f"{path}:1: generate_launch_description() did not return within "
                               f"{_PYTHON_LAUNCH_SECONDS} s") from None
        marker = done.stdout.rfind(_MARKER)
        if marker < 0:
            last = (done.stderr.strip().splitlines() or ["(no output)"])[-1]
            raise ProjectError(f"{path}:1: the launch file could not be read: {last}")
        answer = json.loads(done.stdout[marker + len(_MARKER):])
        if "error" in answer:
            raise ProjectError(answer["error"])
        self._records(answer["records"], scope)

    def _records(self, records: list[dict[str, Any]], scope: _Scope) -> None:
        keys: dict[int, str] = {}
        transitions: dict[int, list[tuple[str, int]]] = {}
        for record in records:
            kind, where = record["kind"], record["where"]
            if kind in ("node", "process"):
                request = self._python_node(record)
                if request is None:
                    continue
                keys[record["id"]] = self.add_node(request)
            elif kind == "container":
                self.notes.append(f"{where}: container {record['name']}: its components run as threads of one "
                                  "process target; the container program itself is not started")
            elif kind == "component":
                self.add_node(self._component(record))
            elif kind == "include":
                inner = _Scope(record["namespace"], dict(map(tuple, record["remap"])), dict(record["env"]),
                               dict(record["args"]), self._merged(record["params"], "", where))
                file = Path(record["file"])
                if not _is_file(file):
                    raise ProjectError(f"{where}: included launch file {file} does not exist")
                self.read(file, inner)
            elif kind == "required":
                self.project["nodes"][self._key_of(keys, record)]["required"] = True
            elif kind == "transition":
                transitions.setdefault(record["id"], []).append((where, record["transition"]))
            elif kind in ("note", "log"):
                self.notes.append(f"{where}: {record['text']}" if kind == "note" else f"launch says: {record['text']}")
        for node_id, steps in transitions.items():
            key = self._key_of(keys, {"id": node_id, "where": steps[0][0]})
            node = self.project["nodes"][key]
            state = node.get("lifecycle", "unconfigured")
            for where, transition in steps:
                state = lifecycle_state_after(state, transition, f"{where}: node {key}")
            node["lifecycle"] = state

    def _key_of(self, keys: dict[int, str], record: dict[str, Any]) -> str:
        if record["id"] not in keys:
            raise ProjectError(f"{record['where']}: the event names an action that starts no node of this launch")
        return keys[record["id"]]

    def _python_node(self, record: dict[str, Any]) -> NodeRequest | None:
        where = record["where"]
        if record["kind"] == "process" and record["package"] is None:
            program = record["args"][0] if record["args"] else "?"
            raise ProjectError(f"{where}: ExecuteProcess of {program!r}: hetros runs a package's own executables "
                               "(ExecutableInPackage, or `ros2 run PACKAGE EXECUTABLE`), not other programs; run "
                               f"{Path(program).name} beside the launch")
        name = record.get("name") or ""
        request = NodeRequest(where=where, package=record["package"], executable=record["executable"], name=name,
                              namespace=join_namespace("", record.get("namespace") or ""),
                              env=record.get("env", {}), args=[*record.get("args", [])],
                              respawn=bool(record.get("respawn")))
        if record["kind"] == "node":
            if record.get("ros_args"):
                request.args += ["--ros-args", *record["ros_args"]]
            request.remap = dict(map(tuple, record["remap"]))
            request.lifecycle = ("active" if record.get("autostart") else "unconfigured") \
                if record.get("lifecycle") else None
            if not name:  # a parameter file's entries are for the name the node will have: its code's
                found = self._code(request.package, self.find_package(request.package, where), request.executable,
                                   where, {})
                name = found.ros_names[0] if len(set(found.ros_names)) == 1 else found.key
            request.params = self._merged(record["parameters"], join_namespace(request.namespace, name), where)
        return request

    def _component(self, record: dict[str, Any]) -> NodeRequest:
        """A component of a container (launch_ros's ComposableNode). ROS 2's components are C++ plugins
        that rclcpp_components loads into one process; a Python package offers its node classes under the
        ``rclpy_components`` entry point group (``'pkg::Talker = pkg.talker:Talker'``), and the
        components of one container become threads of one process target."""
        name = record.get("name") or ""
        request = NodeRequest(where=record["where"], package=record["package"], executable="", name=name,
                              namespace=join_namespace("", record.get("namespace") or ""),
                              remap=dict(map(tuple, record["remap"])), plugin=record["plugin"],
                              container=record["container"])
        if not name:
            found = self._code(request.package, self.find_package(request.package, request.where), request.plugin,
                               request.where, {}, "rclpy_components")
            name = found.ros_names[0] if len(set(found.ros_names)) == 1 else found.key
        request.params = self._merged(record["parameters"], join_namespace(request.namespace, name), request.where)
        return request

    def _merged(self, entries: list[Any], full_name: str, where: str) -> dict[str, Any]:
        """A node's parameters from launch_ros's entries, in order: values, and files' values for this node."""
        merged: dict[str, Any] = {}
        for entry in entries:
            if isinstance(entry, (list, tuple)):  # (name, value) pairs of SetParameter, or ({"file": f}, None)
                entry = entry[0] if isinstance(entry[0], dict) else {"values": {entry[0]: entry[1]}}
            if "values" in entry:
                merged.update(entry["values"])
            else:
                merged.update(ros2_parameter_file(Path(entry["file"]), full_name, where))
        return merged

    # -- helpers -----------------------------------------------------------------------------

    def _code(self, name: str, folders: list[Path], executable: str, where: str, parameters: dict[str, Any],
              group: str = "console_scripts") -> Any:
        if self.ros2:
            targets: dict[str, str] = {}
            for package in folders:
                targets = entry_points(package, group)
                if executable in targets:
                    self.used_packages[package] = None
                    self.imported_from[package] = None
                    key = executable.rpartition("::")[2].lower() if group == "rclpy_components" else executable
                    return scan_ros_entry(package, key, targets[executable], parameters)
            if group == "rclpy_components":
                raise ProjectError(f"{where}: package {name} offers no component {executable!r} (its "
                                   f"rclpy_components: {', '.join(sorted(targets)) or 'none'}); a Python package "
                                   "offers a node class as a component in setup.py: entry_points={'rclpy_components':"
                                   f" ['{executable} = module:NodeClass']}}")
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

    def _parameters(self, element: _Element, scope: _Scope, path: Path,
                    keep_absolute: bool = False) -> dict[str, Any]:
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
            data = load_yaml(source, f"{where}: parameter file", error=ProjectError)
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
        value = _value(self.attribute(element, "value", scope, path), where)
        kind = element.attributes.get("type")
        if kind in ("str", "string"):
            value = str(self.attribute(element, "value", scope, path))
        return {name if keep_absolute and name.startswith("/") else name.lstrip("/~"): value}


_PYTHON_LAUNCH_SECONDS = 60
_MARKER = "\n@@hetros-launch@@"  # hetros.compat.launch_eval's: that module is not imported here

def lifecycle_state_after(state: str, transition: int, where: str) -> str:
    """The state a managed node is in after ``transition`` from ``state``, as the launch asks it."""
    if transition not in LIFECYCLE_TRANSITIONS:
        raise ProjectError(f"{where}: transition {transition} is not one a launch asks (1 configure, 2 cleanup, "
                           "3 activate, 4 deactivate, 5-7 shutdown)")
    _, start, end = LIFECYCLE_TRANSITIONS[transition]
    if start != state:
        raise ProjectError(f"{where}: transition {transition} starts from {start}, but the node is {state} then")
    return end


def ros2_parameter_file(path: Path, full_name: str, where: str) -> dict[str, Any]:
    """What a ROS 2 parameter file gives the node ``full_name`` (``/ns/name``), as a launch reads it for the
    node: :func:`parameters_from_files`, its errors named with the launch file's line."""
    try:
        return parameters_from_files([path], full_name)
    except ProjectError as exc:
        raise ProjectError(f"{where}: {exc}") from None


def _is_file(path: Path) -> bool:
    """Whether ``path`` names a file; a name the system cannot even look up (too long) names none."""
    try:
        return path.is_file()
    except OSError:
        return False


def _package_of(launch_file: Path) -> Path | None:
    """The package folder (its package.xml) a launch file belongs to, or None."""
    for above in launch_file.parents:
        if (above / "package.xml").is_file():
            return above
    return None


def package_search_path(launch_file: Path) -> list[Path]:
    """Where a launch file's packages are looked for besides ``--package-path``: ``$HETROS_PACKAGE_PATH``
    (folders, as ROS's prefix paths), the launch file's folder, and the folder holding the package the
    launch file belongs to (``pkg/launch/x_launch.py``: beside ``pkg``)."""
    found = [Path(p) for p in os.environ.get("HETROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    folder = launch_file.resolve().parent
    found.append(folder)
    for above in folder.parents:
        if (above / "package.xml").is_file():
            found.append(above.parent)
            break
    return found


def import_launch(path: Path, ros2: bool, package_paths: list[Path], base: Path,
                  args: dict[str, str] | None = None) -> tuple[dict[str, Any], LaunchNotes]:
    """The project a ROS 1 (``ros2=False``) or ROS 2 launch file describes, and notes on what the scan of
    its nodes' code could not follow (with the widest mode the project's file may be written with)."""
    importer = LaunchImporter(ros2, [*package_paths, *package_search_path(path)], base)
    importer.read(path, _Scope(args=dict(args or {})))
    importer.project = {**code_folders(base, importer.imported_from, importer.used_packages), **importer.project}
    if not importer.project.get("topics"):
        importer.project.pop("topics", None)
    if not importer.project["nodes"]:
        raise ProjectError(f"{path}:1: the launch file starts no node")
    name = re.sub(r"[^A-Za-z0-9_-]", "_", path.name.split(".")[0]).lstrip("_-0123456789") or "launch"
    return {"name": name, **importer.project}, importer.notes
