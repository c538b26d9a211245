"""launch_ros.actions: ROS nodes and the scope they start in (namespace, remaps, parameters).

As in launch_ros, the scope lives in the launch configurations (``ros_namespace``, ``ros_remaps``,
``global_params``), so groups scope it; a node action records the node it would start."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import yaml

from ..launch import Action, LaunchContext, LaunchFileError, Substitution
from ..launch.actions import changed_environment
from ..launch.utilities import normalize_to_list_of_substitutions, perform_substitutions
from .descriptions import ComposableNode, Parameter, ParameterFile, ParameterValue


def _text(context: LaunchContext, value: Any) -> str:
    return perform_substitutions(context, normalize_to_list_of_substitutions(value))


def _optional(context: LaunchContext, value: Any) -> str | None:
    return None if value is None else _text(context, value)


def _is_substitutions(value: Any) -> bool:
    if isinstance(value, Substitution):
        return True
    return isinstance(value, (list, tuple)) and bool(value) and \
        all(isinstance(item, (str, Substitution)) for item in value) and \
        any(isinstance(item, Substitution) for item in value)


def _value(context: LaunchContext, value: Any) -> Any:
    """A parameter's value as launch_ros evaluates it: a substitution's text read as YAML (``'true'`` is a
    bool) unless ``ParameterValue(value_type=str)``; lists element by element."""
    if isinstance(value, ParameterValue):
        if value.value_type is str:
            return _text(context, value.value)
        return _value(context, value.value)
    if _is_substitutions(value):
        text = _text(context, value)
        try:
            return yaml.safe_load(text) if text else text
        except yaml.YAMLError:
            return text
    if isinstance(value, (list, tuple)):
        return [_value(context, item) for item in value]
    if isinstance(value, Path):
        return str(value)
    return value


def _flat(context: LaunchContext, values: dict[Any, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in values.items():
        name = prefix + _text(context, key)
        if isinstance(value, dict):
            out.update(_flat(context, value, f"{name}."))
        else:
            out[name] = _value(context, value)
    return out


def evaluate_parameters(context: LaunchContext, parameters: Any, where: str) -> list[dict[str, Any]]:
    """Each entry as ``{"values": {...}}`` or ``{"file": path}``, in order (later entries win)."""
    out: list[dict[str, Any]] = []
    for entry in parameters or []:
        if isinstance(entry, dict):
            out.append({"values": _flat(context, entry)})
        elif isinstance(entry, Parameter):
            out.append({"values": {_text(context, entry.name): _value(context, entry.value)}})
        elif isinstance(entry, ParameterFile):
            out.append({"file": _text(context, entry.param_file)})
        elif isinstance(entry, (str, Path, Substitution, list, tuple)):
            out.append({"file": _text(context, entry)})
        else:
            raise LaunchFileError(f"{where}: a parameter entry is a dict, a file or a ParameterFile, not {entry!r}")
    return out


def _remaps(context: LaunchContext, remappings: Any) -> list[list[str]]:
    return [[_text(context, src), _text(context, dst)] for src, dst in remappings or []]


def _namespace(context: LaunchContext, namespace: str | None) -> str:
    """The node's namespace under the pushed one: an absolute namespace stands alone."""
    pushed = str(context.launch_configurations.get("ros_namespace", ""))
    if namespace is None or namespace == "":
        return pushed
    if namespace.startswith("/"):
        return namespace
    return f"{pushed.rstrip('/')}/{namespace}"


class Node(Action):
    def __init__(self, *, executable: Any, package: Any = None, name: Any = None, namespace: Any = None,
                 exec_name: Any = None, parameters: Any = None, remappings: Any = None, ros_arguments: Any = None,
                 arguments: Any = None, respawn: Any = False, respawn_delay: Any = None, output: Any = "log",
                 additional_env: Any = None, **kwargs: Any) -> None:
        super().__init__(condition=kwargs.pop("condition", None))
        self.node_executable = executable
        self.node_package = package
        self.node_name_given = name
        self.node_namespace = namespace
        self.parameters = parameters
        self.remappings = list(remappings or [])
        self.ros_arguments = list(ros_arguments or [])
        self.arguments = list(arguments or [])
        self.respawn = respawn
        self.additional_env = dict(additional_env or {})
        self._lifecycle = False
        self._autostart: Any = False
        self.on_exit = kwargs.pop("on_exit", None)  # launch's ExecuteProcess(on_exit=Shutdown()): a required node

    def execute(self, context: LaunchContext) -> None:
        if self.node_package is None:
            raise LaunchFileError(f"{self.where}: Node(package=...) is needed: hetros finds the executable in its "
                              "package")
        global_params = [{"values": {k: v}} if not isinstance(k, dict) else k
                         for k, v in context.launch_configurations.get("global_params", [])]
        env = changed_environment(context)
        env.update({_text(context, k): _text(context, v) for k, v in self.additional_env.items()})
        respawn = self.respawn if isinstance(self.respawn, bool) else \
            _text(context, self.respawn).strip().lower() in ("true", "1")
        context.record(
            "node", self.where, id=id(self), package=_text(context, self.node_package),
            executable=_text(context, self.node_executable), name=_optional(context, self.node_name_given),
            namespace=_namespace(context, _optional(context, self.node_namespace)),
            remap=[*context.launch_configurations.get("ros_remaps", []), *_remaps(context, self.remappings)],
            parameters=[*global_params, *evaluate_parameters(context, self.parameters, self.where)],
            args=[_text(context, a) for a in self.arguments], ros_args=[_text(context, a) for a in self.ros_arguments],
            env=env, respawn=respawn, lifecycle=self._lifecycle,
            autostart=self._autostart if isinstance(self._autostart, bool) else
            _text(context, self._autostart).strip().lower() in ("true", "1"))
        if self.on_exit is not None:
            from ..launch.event_handlers import OnProcessExit

            context.pending.extend(OnProcessExit(target_action=self, on_exit=self.on_exit).entities_now(
                context, self.where))


class LifecycleNode(Node):
    """A managed node: started unconfigured; launch's transitions (ChangeState events, ``autostart``) say
    which state the launch brings it to."""

    def __init__(self, *, name: Any, namespace: Any, autostart: Any = False, **kwargs: Any) -> None:
        super().__init__(name=name, namespace=namespace, **kwargs)
        self._lifecycle = True
        self._autostart = autostart


class PushRosNamespace(Action):
    def __init__(self, namespace: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.namespace = namespace

    def execute(self, context: LaunchContext) -> None:
        context.launch_configurations["ros_namespace"] = _namespace(context, _text(context, self.namespace))


PushROSNamespace = PushRosNamespace


class SetRemap(Action):
    def __init__(self, src: Any, dst: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.src, self.dst = src, dst

    def execute(self, context: LaunchContext) -> None:
        remaps = list(context.launch_configurations.get("ros_remaps", []))
        remaps.append([_text(context, self.src), _text(context, self.dst)])
        context.launch_configurations["ros_remaps"] = remaps


class SetParameter(Action):
    def __init__(self, name: Any, value: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.name, self.value = name, value

    def execute(self, context: LaunchContext) -> None:
        params = list(context.launch_configurations.get("global_params", []))
        params.append((_text(context, self.name), _value(context, self.value)))
        context.launch_configurations["global_params"] = params


class SetUseSimTime(SetParameter):
    def __init__(self, value: Any, **kwargs: Any) -> None:
        super().__init__("use_sim_time", value, **kwargs)


class SetParametersFromFile(Action):
    def __init__(self, filename: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.filename = filename

    def execute(self, context: LaunchContext) -> None:
        params = list(context.launch_configurations.get("global_params", []))
        params.append(({"file": _text(context, self.filename)}, None))
        context.launch_configurations["global_params"] = params


def _record_components(context: LaunchContext, container: str, where: str,
                       descriptions: Iterable[ComposableNode]) -> None:
    for component in descriptions:
        if component.condition is not None and not component.condition.evaluate(context):
            continue
        context.record(
            "component", component.where, container=container, package=_text(context, component.package),
            plugin=_text(context, component.plugin), name=_optional(context, component.name),
            namespace=_namespace(context, _optional(context, component.namespace)),
            remap=[*context.launch_configurations.get("ros_remaps", []), *_remaps(context, component.remappings)],
            parameters=evaluate_parameters(context, component.parameters, component.where))


class ComposableNodeContainer(Node):
    """A container process: its components become threads of one process target."""

    def __init__(self, *, name: Any, namespace: Any, composable_node_descriptions: Any = None,
                 **kwargs: Any) -> None:
        kwargs.setdefault("executable", "component_container")
        kwargs.setdefault("package", "rclcpp_components")
        super().__init__(name=name, namespace=namespace, **kwargs)
        self.descriptions = list(composable_node_descriptions or [])

    def execute(self, context: LaunchContext) -> None:
        name = _text(context, self.node_name_given)
        full = f"{_namespace(context, _optional(context, self.node_namespace)).rstrip('/')}/{name}"
        context.record("container", self.where, name=full)
        _record_components(context, full, self.where, self.descriptions)


class LoadComposableNodes(Action):
    def __init__(self, *, composable_node_descriptions: Any, target_container: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.descriptions = list(composable_node_descriptions)
        self.target_container = target_container

    def execute(self, context: LaunchContext) -> None:
        target = self.target_container
        if isinstance(target, ComposableNodeContainer):
            name = _text(context, target.node_name_given)
            full = f"{_namespace(context, _optional(context, target.node_namespace)).rstrip('/')}/{name}"
        else:
            full = _text(context, target)
            full = full if full.startswith("/") else f"/{full}"
        _record_components(context, full, self.where, self.descriptions)


__all__ = [
    "ComposableNodeContainer",
    "LifecycleNode",
    "LoadComposableNodes",
    "Node",
    "PushROSNamespace",
    "PushRosNamespace",
    "SetParameter",
    "SetParametersFromFile",
    "SetRemap",
    "SetUseSimTime",
    "evaluate_parameters",
]
