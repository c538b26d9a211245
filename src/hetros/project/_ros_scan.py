"""``hetros init`` for code written for ROS: rclpy and rospy nodes found by reading their sources.

A package's nodes are its entry points (``console_scripts`` in ``setup.py`` or ``setup.cfg``) and
its scripts that call ``rospy.init_node``; a file given alone is a node when it has a ``main``. What
a node creates is read from the syntax tree, nothing is imported: ``Node`` subclasses and
``rclpy.create_node`` with their ``create_publisher(T, 'name', qos)`` calls and friends,
``ActionServer(node, T, 'name')``, rospy's ``Publisher('name', T)`` and friends, followed into the
package's own modules the entry point imports. A name only known at run time becomes a placeholder
naming file:line, which ``hetros check`` refuses until it is replaced.
"""

from __future__ import annotations

import ast
import configparser
import os
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._errors import ProjectError
from .._files import parse_python, read_text
from ..plan import PARAMETER_SERVICES

# placeholders start with this: not a ROS name, so the checks refuse them with their own message
PLACEHOLDER = "?"

_RCLPY_CALLS = {"create_publisher": ("publish", 0, 1, 2), "create_lifecycle_publisher": ("publish", 0, 1, 2),
                "create_subscription": ("subscribe", 0, 1, 3),
                "create_service": ("services", 0, 1, None), "create_client": ("clients", 0, 1, None)}
# call -> (section, index of the type, index of the name): rclpy.action's classes take the node first
_ACTION_CALLS = {"ActionServer": ("actions", 1, 2), "ActionClient": ("action_clients", 1, 2)}
# rospy: (section, index of the name, index of the type)
_ROSPY_CALLS = {"Publisher": ("publish", 0, 1), "Subscriber": ("subscribe", 0, 1), "Service": ("services", 0, 1),
                "ServiceProxy": ("clients", 0, 1)}
# tf2_ros's classes and the topics each opens (ROS 1's and ROS 2's alike), with the QoS tf2_ros gives them
_TF2_CALLS = {"TransformListener": (("subscribe", "/tf"), ("subscribe", "/tf_static")),
              "TransformBroadcaster": (("publish", "/tf"),), "StaticTransformBroadcaster": (("publish", "/tf_static"),)}
TF2_QOS = {"/tf": {"history": "keep_last", "depth": 100},
           "/tf_static": {"history": "keep_last", "depth": 100, "durability": "transient_local"}}
# the services rclpy's enable_logger_service=True gives a node, under its name
LOGGER_SERVICES = {"get_logger_levels": "rcl_interfaces/srv/GetLoggerLevels",
                   "set_logger_levels": "rcl_interfaces/srv/SetLoggerLevels"}
_PRESETS = {"qos_profile_sensor_data": {"reliability": "best_effort", "history": "keep_last", "depth": 5},
            "qos_profile_system_default": {"history": "keep_last", "depth": 10},
            "qos_profile_services_default": {"history": "keep_last", "depth": 10}}


@dataclass
class RosNode:
    """One node as ``hetros init`` writes it."""

    key: str
    run: str
    ros_names: list[str] = field(default_factory=list)
    endpoints: dict[str, dict[str, str]] = field(default_factory=dict)
    qos: dict[str, dict[str, Any]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    managed: bool = False  # a managed node (an rclpy.lifecycle Node): it starts unconfigured
    # the delivery policies its endpoints choose in code: (section, topic, policies, file:line)
    chosen: list[tuple[str, str, dict[str, str], str]] = field(default_factory=list)


def entry_points(package: Path, group: str = "console_scripts") -> dict[str, str]:
    """An entry point group's name -> ``module:attribute`` from setup.py and setup.cfg: ``console_scripts``
    (a package's executables) or ``rclpy_components`` (its components: plugin name -> node class)."""
    found: dict[str, str] = {}
    setup_py = package / "setup.py"
    if setup_py.is_file():
        tree, names = _setup_py(setup_py)
        for table in ast.walk(tree):
            if not isinstance(table, ast.Dict):
                continue
            for key, value in zip(table.keys, table.values, strict=True):
                if key is not None and _string(key) == group and isinstance(value, ast.List):
                    for item in value.elts:
                        name, sep, target = (_joined(item, names) or "").partition("=")
                        if sep:
                            found[name.strip()] = target.strip()
    setup_cfg = package / "setup.cfg"
    if setup_cfg.is_file():
        parser = configparser.ConfigParser()
        parser.read(setup_cfg, encoding="utf-8")
        if parser.has_option("options.entry_points", group):
            for line in parser.get("options.entry_points", group).splitlines():
                name, sep, target = line.partition("=")
                if sep:
                    found[name.strip()] = target.strip()
    return found


def _setup_py(setup_py: Path) -> tuple[ast.Module, dict[str, str]]:
    """setup.py's syntax tree, and its module-level names bound to strings (``package_name = '...'``):
    what its other strings are built from."""
    tree = parse_python(setup_py, "setup.py", error=ProjectError)
    names: dict[str, str] = {}
    for stmt in tree.body:
        if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1 and isinstance(stmt.targets[0], ast.Name):
            if (text := _joined(stmt.value, names)) is not None:
                names[stmt.targets[0].id] = text
    return tree, names


def data_files(package: Path) -> list[tuple[str, list[str]]]:
    """setup.py's ``data_files``: (folder under the install prefix, [files relative to the package]), as
    far as they are literal (what ``get_package_share_directory`` lays out)."""
    setup_py = package / "setup.py"
    if not setup_py.is_file():
        return []
    tree, names = _setup_py(setup_py)
    found: list[tuple[str, list[str]]] = []
    for call in ast.walk(tree):
        if not isinstance(call, ast.Call):
            continue
        for keyword in call.keywords:
            if keyword.arg != "data_files" or not isinstance(keyword.value, ast.List | ast.Tuple):
                continue
            for entry in keyword.value.elts:
                if isinstance(entry, ast.Tuple) and len(entry.elts) == 2 and \
                        isinstance(files := entry.elts[1], ast.List | ast.Tuple):
                    folder = _joined(entry.elts[0], names)
                    listed = [text for item in files.elts if (text := _joined(item, names)) is not None]
                    if folder is not None:
                        found.append((folder, listed))
    return found


def package_name(package: Path) -> str:
    """The package's name from package.xml (else its folder's name)."""
    xml = package / "package.xml"
    if xml.is_file():
        found = re.search(r"<name>\s*([\w-]+)\s*</name>", read_text(xml, "package.xml", error=ProjectError))
        if found:
            return found.group(1)
    return package.name


def _module_file(root: Path, module: str) -> Path | None:
    for candidate in (root.joinpath(*module.split(".")).with_suffix(".py"),
                      root.joinpath(*module.split("."), "__init__.py")):
        if candidate.is_file():
            return candidate
    return None


class _Reader:
    """What one module creates, and where its names come from."""

    def __init__(self, path: Path, root: Path, parameters: dict[str, Any] | None = None) -> None:
        self.path = path
        self.root = root
        self.parameters = parameters or {}
        self.tree = parse_python(path, "ROS node source", error=ProjectError)
        self.types: dict[str, str] = {}  # local name -> pkg/kind/Type
        self.imported: dict[str, str] = {}  # local name -> module it comes from (the package's own)
        self.starred: list[str] = []  # pkg/kind of `from pkg.srv import *`
        for stmt in ast.walk(self.tree):
            if isinstance(stmt, ast.ImportFrom) and stmt.module:
                parts = stmt.module.split(".")
                if len(parts) == 2 and parts[1] in ("msg", "srv", "action") and stmt.names[0].name == "*":
                    self.starred.append(f"{parts[0]}/{parts[1]}")
                    continue
                for alias in stmt.names:
                    local = alias.asname or alias.name
                    if len(parts) == 2 and parts[1] in ("msg", "srv", "action"):
                        self.types[local] = f"{parts[0]}/{parts[1]}/{alias.name}"
                    elif _module_file(root, stmt.module) is not None:
                        self.imported[local] = stmt.module
        # the names message_filters' Subscriber goes by here (``message_filters.Subscriber`` and imported ones)
        self.filter_subscribers = {alias.asname or alias.name for stmt in ast.walk(self.tree)
                                   if isinstance(stmt, ast.ImportFrom) and stmt.module == "message_filters"
                                   for alias in stmt.names if alias.name == "Subscriber"}
        self.from_parameters = _from_parameters(self.tree, self.parameters)
        self.constants = {**_constants(self.tree), **{k: text for k, (text, _) in self.from_parameters.items()}}
        self.classes = {s.name: s for s in self.tree.body if isinstance(s, ast.ClassDef)}
        self.functions = {s.name: s for s in self.tree.body if isinstance(s, ast.FunctionDef | ast.AsyncFunctionDef)}

    def _lifecycle_base(self, base: ast.expr) -> bool:
        """Whether a class base is rclpy's managed node (``rclpy.lifecycle.Node``, ``LifecycleNode``)."""
        text = ast.unparse(base)
        if text in ("LifecycleNode", "lifecycle.Node", "rclpy.lifecycle.Node", "rclpy.lifecycle.LifecycleNode"):
            return True
        return text == "Node" and any(isinstance(stmt, ast.ImportFrom) and stmt.module == "rclpy.lifecycle" and
                                      any(a.name == "Node" and (a.asname or a.name) == "Node" for a in stmt.names)
                                      for stmt in self.tree.body)

    def where(self, node: ast.AST) -> str:
        return f"{self.path.name}:{getattr(node, 'lineno', 0)}"

    def type_of(self, expr: ast.expr, kind: str) -> str:
        if isinstance(expr, ast.Name) and expr.id in self.types:
            return self.types[expr.id]
        starred = [m for m in self.starred if m.endswith(f"/{kind}")]
        if isinstance(expr, ast.Name) and len(starred) == 1:
            return f"{starred[0]}/{expr.id}"  # from pkg.srv import *
        if isinstance(expr, ast.Attribute) and isinstance(expr.value, ast.Name):
            return f"{expr.value.id}/{expr.attr}"
        dotted = ast.unparse(expr).split(".")
        if len(dotted) == 3 and dotted[1] == kind:  # import std_msgs.msg ... std_msgs.msg.String
            return "/".join(dotted)
        return f"{PLACEHOLDER}type of {ast.unparse(expr)} at {self.where(expr)}"

    def collect(self, scope: ast.AST, node: RosNode, seen: set[str], bound: dict[str, str] | None = None) -> None:
        """The endpoints ``scope`` creates, following the package's classes and functions it uses.

        ``bound``: the strings ``scope``'s parameters (and ``self.<attr>`` set from them) hold in the call
        that led here, so ``Talker('chatter')`` names the topic its ``__init__(self, topic_name)`` uses."""
        names = {**self.constants, **(bound or {})}
        if isinstance(scope, ast.ClassDef):
            names |= _attributes(scope, names)
            node.managed |= any(self._lifecycle_base(base) for base in scope.bases)
        for call in ast.walk(scope):
            if not isinstance(call, ast.Call):
                continue
            callee = call.func.attr if isinstance(call.func, ast.Attribute) else \
                call.func.id if isinstance(call.func, ast.Name) else ""
            if callee in _RCLPY_CALLS and isinstance(call.func, ast.Attribute) and len(call.args) >= 2:
                section, type_at, name_at, qos_at = _RCLPY_CALLS[callee]
                self._add(node, section, call, call.args[type_at], call.args[name_at],
                          call.args[qos_at] if qos_at is not None and len(call.args) > qos_at else
                          _keyword(call, "qos_profile"), names)
            elif callee in _ACTION_CALLS and len(call.args) >= 3:
                section, type_at, name_at = _ACTION_CALLS[callee]
                self._add(node, section, call, call.args[type_at], call.args[name_at], None, names)
            elif self._filter_subscriber(call) and len(call.args) >= 2:
                rospy_form = isinstance(call.args[0], ast.Constant) and isinstance(call.args[0].value, str)
                type_at, name_at = (1, 0) if rospy_form else (1, 2)
                if len(call.args) > max(type_at, name_at):
                    self._add(node, "subscribe", call, call.args[type_at], call.args[name_at],
                              None if rospy_form or len(call.args) < 4 else call.args[3], names)
            elif callee in _TF2_CALLS:
                for section, topic in _TF2_CALLS[callee]:
                    node.endpoints.setdefault(section, {})[topic] = "tf2_msgs/msg/TFMessage"
                    node.qos[topic] = dict(TF2_QOS[topic])
            elif callee == "AsyncParameterClient" and len(call.args) >= 2:
                self._parameter_client(node, call, names)
            elif callee in _ROSPY_CALLS and _is_rospy(call.func) and len(call.args) >= 2:
                section, name_at, type_at = _ROSPY_CALLS[callee]
                self._add(node, section, call, call.args[type_at], call.args[name_at], _keyword(call, "queue_size"),
                          names)
            elif (callee in ("init_node", "create_node") or (callee == "__init__" and  # super().__init__('name')
                  isinstance(call.func, ast.Attribute))) and call.args:
                node.ros_names.append(_joined(call.args[0], names) or "")
                self._logger_services(node, call, node.ros_names[-1])
            elif callee in self.classes and callee not in seen:
                cls = self.classes[callee]
                self.collect(cls, node, seen | {callee}, _arguments(call, _init_of(cls), names))
            elif callee in self.functions and callee not in seen:
                function = self.functions[callee]
                self.collect(function, node, seen | {callee}, _arguments(call, function, names))
            elif callee in self.imported and callee not in seen:
                path = _module_file(self.root, self.imported[callee])
                if path is not None:
                    other = _Reader(path, self.root, self.parameters)
                    found = other.classes.get(callee) or other.functions.get(callee)
                    if found is not None:
                        init = _init_of(found) if isinstance(found, ast.ClassDef) else found
                        other.collect(found, node, seen | {callee}, _arguments(call, init, names))

    def _filter_subscriber(self, call: ast.Call) -> bool:
        """``message_filters.Subscriber(...)``, or the class imported under some name."""
        func = call.func
        if isinstance(func, ast.Attribute):
            return func.attr == "Subscriber" and isinstance(func.value, ast.Name) and func.value.id == "message_filters"
        return isinstance(func, ast.Name) and func.id in self.filter_subscribers

    @staticmethod
    def _logger_services(node: RosNode, call: ast.Call, ros_name: str) -> None:
        """rclpy's ``Node(name, enable_logger_service=True)`` serves its logger levels under its name."""
        enabled = _keyword(call, "enable_logger_service")
        if ros_name and isinstance(enabled, ast.Constant) and enabled.value is True:
            services = node.endpoints.setdefault("services", {})
            for service, typename in LOGGER_SERVICES.items():
                services[f"{ros_name}/{service}"] = typename

    def _parameter_client(self, node: RosNode, call: ast.Call, names: dict[str, str]) -> None:
        """rclpy's ``AsyncParameterClient(node, 'other')`` calls the six parameter services of ``other``."""
        remote = _joined(call.args[1], names)
        clients = node.endpoints.setdefault("clients", {})
        if remote is None:
            place = self.where(call)
            clients[f"{PLACEHOLDER}{ast.unparse(call.args[1])} at {place}"] = "rcl_interfaces/srv/GetParameters"
            node.notes.append(f"{place}: AsyncParameterClient names the node whose parameters it reaches at run "
                              "time; replace the placeholder under nodes.{node}.clients with that node's six "
                              "parameter services (<name>/get_parameters and the rest)")
            return
        for service, typename in PARAMETER_SERVICES.items():
            clients[f"{remote}/{service}"] = typename

    def _add(self, node: RosNode, section: str, call: ast.Call, type_expr: ast.expr, name_expr: ast.expr,
             qos: ast.expr | None, names: dict[str, str]) -> None:
        name = _joined(name_expr, names)
        kind = {"services": "srv", "clients": "srv", "actions": "action", "action_clients": "action"}.get(section,
                                                                                                          "msg")
        typename = self.type_of(type_expr, kind)
        if typename.count("/") == 2 and f"/{kind}/" not in typename:
            typename = f"{PLACEHOLDER}{typename} is not a {kind} type ({self.where(call)})"
        if name is None:
            name = f"{PLACEHOLDER}{ast.unparse(name_expr)} at {self.where(call)}"
            node.notes.append(f"{self.where(call)}: {ast.unparse(call.func)}(..., {ast.unparse(name_expr)}) names its "
                              f"{section} endpoint at run time; replace the placeholder under nodes.{{node}}."
                              f"{section} with the name (hetros check refuses it until then)")
        key = ast.unparse(name_expr)
        if key in self.from_parameters and not name.startswith(PLACEHOLDER):
            parameter = self.from_parameters[key][1]
            node.notes.append(f"{self.where(call)}: the {section} endpoint is named by parameter {parameter!r}: "
                              f"written as {name!r}, its value here; a project that sets the parameter to another "
                              f"name must rename the endpoint under nodes.{{node}}.{section} too")
        node.endpoints.setdefault(section, {})[name] = typename
        if section in ("publish", "subscribe") and qos is not None:
            described = _qos(qos)
            if described:
                node.qos[name] = described
            if chosen := chosen_delivery(qos):
                node.chosen.append((section, name, chosen, self.where(call)))


def _constants(tree: ast.AST) -> dict[str, str]:
    """The names the module binds to one string only, wherever (``TOPIC = "chatter"`` at the top,
    ``topic = "chatter"`` in a function): a topic named through one is as good as the string. A name
    bound anywhere else (a parameter, a loop, another value) is not one."""
    strings: dict[int, str | None] = {}
    for stmt in ast.walk(tree):
        if isinstance(stmt, ast.Assign | ast.AnnAssign) and stmt.value is not None:
            for target in stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]:
                strings[id(target)] = _string(stmt.value)
    bound: dict[str, set[str | None]] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            bound.setdefault(node.id, set()).add(strings.get(id(node)))
        elif isinstance(node, ast.arg):
            bound.setdefault(node.arg, set()).add(None)
    return {name: value for name, values in bound.items() if len(values) == 1 and (value := next(iter(values)))}


_PARAMETER_CALLS = ("get_param", "declare_parameter", "get_parameter", "get_parameter_or")


def _from_parameters(tree: ast.AST, parameters: dict[str, Any]) -> dict[str, tuple[str, str]]:
    """Names bound once to a parameter's text (``topic = rospy.get_param('~topic_name')``,
    ``self.declare_parameter('topic', 'chatter').value``): its value where the launch file gives it,
    else the default the code names; and the parameter's name."""
    found: dict[str, tuple[str, str] | None] = {}
    for stmt in ast.walk(tree):
        if not isinstance(stmt, ast.Assign) or len(stmt.targets) != 1:
            continue
        target, value = stmt.targets[0], stmt.value
        if isinstance(value, ast.Attribute) and value.attr == "value":
            value = value.value  # rclpy's Parameter(...).value
        if not isinstance(value, ast.Call) or not value.args:
            continue
        callee = value.func.attr if isinstance(value.func, ast.Attribute) else getattr(value.func, "id", "")
        parameter = _string(value.args[0])
        if callee not in _PARAMETER_CALLS or parameter is None:
            continue
        given = parameters.get(parameter.lstrip("~/"))
        text = str(given) if isinstance(given, str | int | float) and not isinstance(given, bool) else \
            (_string(value.args[1]) if len(value.args) > 1 else None)
        key = target.id if isinstance(target, ast.Name) else \
            f"{target.value.id}.{target.attr}" if isinstance(target, ast.Attribute) and \
            isinstance(target.value, ast.Name) else None
        if key is not None:
            entry = None if text is None else (text, parameter)
            found[key] = entry if key not in found or found[key] == entry else None
    return {key: entry for key, entry in found.items() if entry is not None}


def _init_of(cls: ast.ClassDef) -> ast.FunctionDef | ast.AsyncFunctionDef | None:
    return next((s for s in cls.body if isinstance(s, ast.FunctionDef | ast.AsyncFunctionDef)
                 and s.name == "__init__"), None)


def _arguments(call: ast.Call, function: ast.FunctionDef | ast.AsyncFunctionDef | None,
               names: dict[str, str]) -> dict[str, str]:
    """The strings ``call`` passes to ``function``'s parameters, by position (``self`` skipped for a
    method) and by keyword, where the scan can read them."""
    if function is None:
        return {}
    parameters = [a.arg for a in function.args.posonlyargs + function.args.args]
    if parameters and parameters[0] in ("self", "cls"):
        parameters = parameters[1:]
    passed: dict[str, str] = {}
    for parameter, argument in zip(parameters, call.args, strict=False):
        if (text := _joined(argument, names)) is not None:
            passed[parameter] = text
    for keyword in call.keywords:
        if keyword.arg is not None and (text := _joined(keyword.value, names)) is not None:
            passed[keyword.arg] = text
    for parameter, default in zip(reversed(parameters), reversed(function.args.defaults), strict=False):
        if parameter not in passed and (text := _string(default)) is not None:
            passed[parameter] = text
    return passed


def _attributes(cls: ast.ClassDef, names: dict[str, str]) -> dict[str, str]:
    """``self.<attr>`` a class sets once, in ``__init__``, to a string the scan knows (a parameter bound
    by the call, a constant)."""
    found: dict[str, str | None] = {}
    for stmt in ast.walk(cls):
        if isinstance(stmt, ast.Assign):
            for target in stmt.targets:
                if isinstance(target, ast.Attribute) and isinstance(target.value, ast.Name) \
                        and target.value.id == "self":
                    key = f"self.{target.attr}"
                    value = _joined(stmt.value, names)
                    found[key] = value if key not in found or found[key] == value else None
    return {key: value for key, value in found.items() if value is not None}


def _is_rospy(func: ast.expr) -> bool:
    return isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name) and func.value.id == "rospy"


def _keyword(call: ast.Call, name: str) -> ast.expr | None:
    return next((k.value for k in call.keywords if k.arg == name), None)


def _joined(expr: ast.expr, names: dict[str, str]) -> str | None:
    """A string constant, a name bound to one, or a ``+`` of those."""
    if isinstance(expr, ast.Name):
        return names.get(expr.id)
    if isinstance(expr, ast.Attribute) and isinstance(expr.value, ast.Name):
        return names.get(f"{expr.value.id}.{expr.attr}")
    if isinstance(expr, ast.BinOp) and isinstance(expr.op, ast.Add):
        left, right = _joined(expr.left, names), _joined(expr.right, names)
        return None if left is None or right is None else left + right
    return _string(expr)


def _string(expr: ast.expr) -> str | None:
    return expr.value if isinstance(expr, ast.Constant) and isinstance(expr.value, str) else None


# the literal values of rclpy's delivery policies, as the QoS they choose
_LITERALS = {"reliability": {"BEST_EFFORT": "best_effort", "RELIABLE": "reliable"},
             "history": {"KEEP_ALL": "keep_all", "KEEP_LAST": "keep_last"},
             "durability": {"TRANSIENT_LOCAL": "transient_local", "VOLATILE": "volatile"}}


def _literal(policy: str, value: ast.expr) -> str | None:
    """``ReliabilityPolicy.BEST_EFFORT`` (or QoSReliabilityPolicy's) as ``best_effort``; None for a value
    computed at run time."""
    text = ast.unparse(value).rsplit(".", 1)[-1]
    return _LITERALS[policy].get(text)


def _qos(expr: ast.expr) -> dict[str, Any]:
    """A QoS the code asks for, as the project's topics: section writes it; {} where the code computes it at
    run time (a QoS in a variable, a policy from its arguments): the scan cannot know it."""
    if isinstance(expr, ast.Constant) and isinstance(expr.value, int) and not isinstance(expr.value, bool):
        return {"history": "keep_last", "depth": max(expr.value, 1)}
    preset = expr.id if isinstance(expr, ast.Name) else expr.attr if isinstance(expr, ast.Attribute) else ""
    if preset in _PRESETS:
        return dict(_PRESETS[preset])
    if isinstance(expr, ast.Call) and getattr(expr.func, "id", getattr(expr.func, "attr", "")) == "QoSProfile":
        out: dict[str, Any] = {"history": "keep_last", "depth": 10}
        for keyword in expr.keywords:
            if keyword.arg == "depth":
                if not isinstance(keyword.value, ast.Constant):
                    return {}
                out["depth"] = keyword.value.value
            elif keyword.arg in _LITERALS:
                value = _literal(keyword.arg, keyword.value)
                if value is None:
                    return {}
                out[keyword.arg] = value
        return out
    return {}


def chosen_delivery(expr: ast.expr | None) -> dict[str, str]:
    """The delivery policies a QoS argument chooses as literals (a preset's reliability and durability, a
    QoSProfile's given ones); a bare depth chooses none."""
    if expr is None:
        return {}
    preset = expr.id if isinstance(expr, ast.Name) else expr.attr if isinstance(expr, ast.Attribute) else ""
    if preset in _PRESETS:
        return {k: str(v) for k, v in _PRESETS[preset].items() if k in ("reliability", "durability")}
    if isinstance(expr, ast.Call) and getattr(expr.func, "id", getattr(expr.func, "attr", "")) == "QoSProfile":
        return {k.arg: value for k in expr.keywords if k.arg in _LITERALS and (value := _literal(k.arg, k.value))}
    return {}


def scan_ros_entry(root: Path, key: str, target: str, parameters: dict[str, Any] | None = None) -> RosNode:
    """The node whose entry point is ``target`` (``module:function``) of the package rooted at ``root``
    (``parameters``: the node's, where a launch file gives them: topics may be named by them)."""
    module, _, function = target.partition(":")
    node = RosNode(key, target)
    path = _module_file(root, module)
    if path is None:
        node.notes.append(f"{target}: module {module} is not under {root}; add its endpoints by hand")
        return node
    reader = _Reader(path, root, parameters)
    scope: ast.AST | None = reader.functions.get(function) or reader.classes.get(function)  # a component's class
    if scope is None:
        node.notes.append(f"{path.name}: no function {function!r} (entry point {key}); add its endpoints by hand")
        return node
    reader.collect(scope, node, {function})
    return node


def scan_ros_script(path: Path, root: Path, base: Path, parameters: dict[str, Any] | None = None) -> RosNode:
    """A rospy script (run as ``__main__``; its path relative to ``base``, the project file's folder): everything
    the file creates."""
    key = re.sub(r"\W", "_", path.stem)
    node = RosNode(key, os.path.relpath(path.resolve(), base.resolve()))
    reader = _Reader(path, root, parameters)
    reader.collect(reader.tree, node, set())
    return node


# ROS APIs with no counterpart in hetros: the name, and why and what to do instead
UNSUPPORTED = {
    "SubscribeListener": "hetros wires every subscriber before the nodes run and sends each message to all of "
                         "them, so a publisher is not told of new peers and cannot publish to one (peer_publish); "
                         "publish to all, on a transient_local topic if late subscribers need the last message",
    "_connection_header": "hetros delivers messages without ROS 1's per-connection headers (callerid, a "
                          "publisher's headers=); carry what the receiver needs in the message itself",
}


def unsupported_uses(path: Path) -> list[str]:
    """``file:line: uses X ...`` for each use of a ROS API hetros has no counterpart for (``UNSUPPORTED``) in
    the ROS code at ``path``: ``hetros check`` refuses the node naming the line, rather than letting it
    fail as it runs."""
    if not writes_ros(path):
        return []
    try:
        tree = parse_python(path, "ROS node source", error=ProjectError)
    except ProjectError:
        return []
    first: dict[str, int] = {}  # each name once, at its first line
    for node in ast.walk(tree):
        name = node.attr if isinstance(node, ast.Attribute) else node.id if isinstance(node, ast.Name) else None
        if name in UNSUPPORTED:
            first[name] = min(first.get(name, 1 << 30), getattr(node, "lineno", 0))
    return [f"{path}:{line}: uses {name}, which hetros has no counterpart for: {UNSUPPORTED[name]}"
            for name, line in sorted(first.items(), key=lambda item: item[1])]


def scan_ros_code(path: Path, run: str, root: Path) -> RosNode:
    """What the ROS code of a node (``run``, found at ``path`` under ``root``) creates, as ``hetros init``
    finds it: its endpoints, and the delivery policies they choose as literals (``chosen``: section, topic
    as the code names it, policies, file:line)."""
    if ":" in run:
        return scan_ros_entry(root, run.partition(":")[0], run)
    return scan_ros_script(path, _package_root(path), root)


def writes_ros(path: Path) -> bool:
    """Whether ``path`` is code written for rclpy or rospy."""
    try:
        text = read_text(path, "source file", error=ProjectError)
    except ProjectError:
        return False
    return re.search(r"^\s*(import|from)\s+(rclpy|rospy)\b", text, re.MULTILINE) is not None


def ros_template(paths: list[Path], name: str, base: Path) -> tuple[dict[str, Any], list[str]]:
    """The project for ROS code: each package's entry points and rospy scripts, or each file given (its
    ``main``, else the whole file as a script); each node on a process of its own, as ``ros2 run`` runs it.
    ``base`` is the folder the project file goes to (scripts are named relative to it)."""
    nodes: list[RosNode] = []
    interfaces: list[Path] = []  # the given packages' own msg/, srv/, action/ folders
    seen: set[Path] = set()  # scripts by their real path: a symlink to one is not a second node
    imported_from: list[Path] = []  # the folders entry points' modules are imported from
    for given in paths:
        if given.is_dir():
            root = given
            imported_from.append(root)
            for key, target in sorted(entry_points(given).items()):
                nodes.append(scan_ros_entry(root, key, target))
            for script in sorted(given.rglob("*"), key=lambda p: (p.is_symlink(), p)):  # real files first
                inside = script.relative_to(given).parts[:-1]
                if any(part in ("test", "tests") for part in inside) or script.resolve() in seen:
                    continue  # a package's tests are no nodes of its graph
                if script.is_file() and script.suffix in ("", ".py") and "setup" not in script.name and \
                        writes_ros(script) and "init_node" in read_text(script, "script", error=ProjectError) and \
                        not any(n.run.partition(":")[0].replace(".", "/") in str(script) for n in nodes):
                    seen.add(script.resolve())
                    nodes.append(scan_ros_script(script, root, base))
            interfaces += sorted({xml.parent for xml in given.rglob("package.xml")
                                  if any((xml.parent / kind).is_dir() for kind in ("msg", "srv", "action"))})
        else:
            root = _package_root(given)
            module = ".".join(given.resolve().relative_to(root.resolve()).with_suffix("").parts)
            reader = _Reader(given, root)
            mains = ["main"] if "main" in reader.functions else [] if _runs_as_script(reader.tree) else \
                [name for name in reader.functions if _makes_a_node(reader, name)]
            if mains:
                imported_from.append(root)
                nodes += [scan_ros_entry(root, given.stem if name == "main" else name, f"{module}:{name}")
                          for name in mains]
            else:
                nodes.append(scan_ros_script(given, root, base))
    project: dict[str, Any] = {"name": name, **code_folders(base, imported_from, interfaces),
                               "targets": {}, "nodes": {}, "topics": {}}
    notes: list[str] = []
    asked: dict[str, dict[str, dict[str, Any]]] = {}  # topic -> node -> the QoS its code asks
    named = [n.ros_names[0] if len(set(n.ros_names)) == 1 else "" for n in nodes]
    for node, ros_name in zip(nodes, named, strict=True):
        # a main that makes one node is named after it; one that makes several (composed), or whose node name
        # another main makes too, after its entry point (the console script's name), as `ros2 run` knows it
        key = unique_key(ros_name if ros_name and named.count(ros_name) == 1 else node.key, project["nodes"])
        project["targets"][key] = {"kind": "process"}
        project["nodes"][key] = _template_entry(node, key, ros_name)
        for topic, qos in node.qos.items():
            if not topic.startswith((PLACEHOLDER, "~")):
                asked.setdefault(topic if topic.startswith("/") else f"/{topic}", {})[key] = qos
        notes += [note.replace("{node}", key) for note in node.notes]
    project["topics"] = _template_topics(asked, notes)
    if not project["topics"]:
        del project["topics"]
    return project, notes


def _template_topics(asked: dict[str, dict[str, dict[str, Any]]], notes: list[str]) -> dict[str, Any]:
    """A topic's QoS where every node that names it asks the same in code; where they differ, none (a
    topic's QoS is every endpoint's), said in a note."""
    topics: dict[str, Any] = {}
    for topic, by_node in asked.items():
        kinds = {repr(sorted(qos.items())) for qos in by_node.values()}
        if len(kinds) == 1:
            topics[topic] = next(iter(by_node.values()))
        else:
            told = "; ".join(f"{node}: {qos}" for node, qos in by_node.items())
            notes.append(f"topic {topic}: its nodes ask different QoS in code ({told}); none written under "
                         "topics: (a topic's QoS is every endpoint's): give it the one it should have there")
    return topics


def _template_entry(node: RosNode, key: str, ros_name: str) -> dict[str, Any]:
    """A found node as ``hetros init`` writes it under ``nodes:``."""
    entry: dict[str, Any] = {"run": node.run, "target": key}
    if ros_name and ros_name != key:
        entry["name"] = ros_name
    for section in ("publish", "subscribe", "services", "clients", "actions", "action_clients"):
        if node.endpoints.get(section):
            entry[section] = dict(node.endpoints[section])
    if node.managed:
        entry["lifecycle"] = "unconfigured"
    return entry


def _runs_as_script(tree: ast.Module) -> bool:
    """Whether a file does something when run: code under ``if __name__ == "__main__":``, or calls at its top
    level (rospy scripts often have no guard)."""
    for stmt in tree.body:
        if isinstance(stmt, ast.If) and "__main__" in ast.unparse(stmt.test):
            return True
        if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Call):
            return True
    return False


def _makes_a_node(reader: _Reader, function: str) -> bool:
    """Whether a top-level function of a file without ``main`` is a ROS main of its own: it makes a node
    (``rclpy.init``, ``create_node``, a ``Node`` subclass, ``rospy.init_node``) or creates endpoints."""
    found = RosNode(function, function)
    reader.collect(reader.functions[function], found, {function})
    return bool(found.ros_names or any(found.endpoints.values()))


def code_folders(base: Path, imported_from: Iterable[Path], packages: Iterable[Path]) -> dict[str, list[str]]:
    """The ``python_path:`` and ``messages:`` of a project file written to ``base`` for code that is imported
    from ``imported_from`` and whose ``packages`` may hold msg/, srv/ and action/ folders (each relative to
    ``base``; a folder that is ``base`` itself needs no python_path entry)."""
    def relative(folders: Iterable[Path]) -> list[str]:
        return list(dict.fromkeys(os.path.relpath(folder.resolve(), base.resolve()) for folder in folders))

    out: dict[str, list[str]] = {}
    if python_path := [folder for folder in relative(imported_from) if folder != "."]:
        out["python_path"] = python_path
    if messages := relative(p for p in packages if any((p / kind).is_dir() for kind in ("msg", "srv", "action"))):
        out["messages"] = messages
    return out


def unique_key(wanted: str, taken: dict[str, Any]) -> str:
    """``wanted`` as a node key (non-word characters to ``_``), numbered when taken."""
    wanted = re.sub(r"\W", "_", wanted)
    key, number = wanted, 2
    while key in taken:
        key, number = f"{wanted}_{number}", number + 1
    return key


def _package_root(path: Path) -> Path:
    """The folder a module path is imported from: above the last folder holding an ``__init__.py``."""
    folder = path.resolve().parent
    while (folder / "__init__.py").is_file():
        folder = folder.parent
    return folder
