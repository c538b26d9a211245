"""launch.actions: what a launch description does, as hetros reads it into a project."""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ._core import (
    Action,
    Condition,
    LaunchContext,
    LaunchDescription,
    LaunchDescriptionEntity,
    LaunchFileError,
    normalize_to_list_of_substitutions,
    perform_substitutions,
)


def _entities(value: Any, where: str) -> list[LaunchDescriptionEntity]:
    if value is None:
        return []
    if isinstance(value, LaunchDescriptionEntity):
        return [value]
    try:
        items = list(value)
    except TypeError:
        raise LaunchFileError(f"{where}: expected launch actions, not {value!r}") from None
    for item in items:
        if not isinstance(item, LaunchDescriptionEntity):
            raise LaunchFileError(f"{where}: expected launch actions, not {item!r}")
    return items


class DeclareLaunchArgument(Action):
    def __init__(self, name: str, *, default_value: Any = None, description: str | None = None,
                 choices: Iterable[str] | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.name = name
        self.default_value = None if default_value is None else normalize_to_list_of_substitutions(default_value)
        self.description = description
        self.choices = None if choices is None else list(choices)

    def execute(self, context: LaunchContext) -> None:
        if self.name not in context.launch_configurations:
            if self.default_value is None:
                raise LaunchFileError(f"{self.where}: launch argument {self.name!r} has no value and no default; pass "
                                  f"{self.name}:=VALUE")
            context.launch_configurations[self.name] = perform_substitutions(context, self.default_value)
        value = str(context.launch_configurations[self.name])
        if self.choices is not None and value not in self.choices:
            raise LaunchFileError(f"{self.where}: launch argument {self.name!r} must be one of {self.choices}, not "
                              f"{value!r}")


class SetLaunchConfiguration(Action):
    def __init__(self, name: Any, value: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.name = normalize_to_list_of_substitutions(name)
        self.value = normalize_to_list_of_substitutions(value)

    def execute(self, context: LaunchContext) -> None:
        context.launch_configurations[perform_substitutions(context, self.name)] = \
            perform_substitutions(context, self.value)


class UnsetLaunchConfiguration(Action):
    def __init__(self, name: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.name = normalize_to_list_of_substitutions(name)

    def execute(self, context: LaunchContext) -> None:
        context.launch_configurations.pop(perform_substitutions(context, self.name), None)


class PushLaunchConfigurations(Action):
    def execute(self, context: LaunchContext) -> None:
        context._push_launch_configurations()


class PopLaunchConfigurations(Action):
    def execute(self, context: LaunchContext) -> None:
        context._pop_launch_configurations()


class ResetLaunchConfigurations(Action):
    """What a group that does not forward keeps: the configurations it names (and hetros's ROS scope)."""

    def __init__(self, launch_configurations: dict[Any, Any] | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.launch_configurations = launch_configurations

    def execute(self, context: LaunchContext) -> None:
        kept = {k: v for k, v in context.launch_configurations.items() if k.startswith("ros_") or
                k == "global_params"}
        for name, value in (self.launch_configurations or {}).items():
            kept[perform_substitutions(context, normalize_to_list_of_substitutions(name))] = \
                perform_substitutions(context, normalize_to_list_of_substitutions(value))
        context.launch_configurations = kept


class PushEnvironment(Action):
    def execute(self, context: LaunchContext) -> None:
        context._push_environment()


class PopEnvironment(Action):
    def execute(self, context: LaunchContext) -> None:
        context._pop_environment()


class ResetEnvironment(Action):
    def execute(self, context: LaunchContext) -> None:
        context._reset_environment()


class SetEnvironmentVariable(Action):
    def __init__(self, name: Any, value: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.name = normalize_to_list_of_substitutions(name)
        self.value = normalize_to_list_of_substitutions(value)

    def execute(self, context: LaunchContext) -> None:
        context.environment[perform_substitutions(context, self.name)] = perform_substitutions(context, self.value)


class UnsetEnvironmentVariable(Action):
    def __init__(self, name: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.name = normalize_to_list_of_substitutions(name)

    def execute(self, context: LaunchContext) -> None:
        context.environment.pop(perform_substitutions(context, self.name), None)


class AppendEnvironmentVariable(Action):
    def __init__(self, name: Any, value: Any, *, prepend: bool = False, separator: str = os.pathsep,
                 **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.name = normalize_to_list_of_substitutions(name)
        self.value = normalize_to_list_of_substitutions(value)
        self.prepend = prepend
        self.separator = separator

    def execute(self, context: LaunchContext) -> None:
        name, value = perform_substitutions(context, self.name), perform_substitutions(context, self.value)
        old = context.environment.get(name)
        parts = [value, old] if self.prepend else [old, value]
        context.environment[name] = self.separator.join(p for p in parts if p)


class GroupAction(Action):
    def __init__(self, actions: Iterable[LaunchDescriptionEntity], *, scoped: bool = True, forwarding: bool = True,
                 launch_configurations: dict[Any, Any] | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.actions = _entities(actions, self.where)
        self.scoped = scoped
        self.forwarding = forwarding
        self.launch_configurations = launch_configurations or {}

    def get_sub_entities(self) -> list[LaunchDescriptionEntity]:
        return list(self.actions)

    def execute(self, context: LaunchContext) -> list[LaunchDescriptionEntity]:
        if not self.scoped:
            return [*(SetLaunchConfiguration(k, v) for k, v in self.launch_configurations.items()), *self.actions]
        start: list[LaunchDescriptionEntity] = [PushLaunchConfigurations(), PushEnvironment()]
        if self.forwarding:
            start += [SetLaunchConfiguration(k, v) for k, v in self.launch_configurations.items()]
        else:
            start.append(ResetLaunchConfigurations(self.launch_configurations))
        return [*start, *self.actions, PopEnvironment(), PopLaunchConfigurations()]


def load_python_launch_file(path: Path, where: str) -> LaunchDescription:
    """The description a Python launch file's ``generate_launch_description()`` gives (the file is the
    user's own code, run as ``ros2 launch`` runs it)."""
    if not path.is_file():
        raise LaunchFileError(f"{where}: launch file {path} does not exist")
    spec = importlib.util.spec_from_file_location(f"_hetros_launch_{abs(hash(str(path)))}", path)
    if spec is None or spec.loader is None:
        raise LaunchFileError(f"{where}: {path} cannot be loaded as Python")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    make = getattr(module, "generate_launch_description", None)
    if not callable(make):
        raise LaunchFileError(f"{path}:1: a Python launch file defines generate_launch_description()")
    description = make()
    if not isinstance(description, LaunchDescription):
        raise LaunchFileError(f"{path}: generate_launch_description() must return a LaunchDescription, not "
                          f"{type(description).__name__}")
    return description


class _EnterFile(Action):
    def __init__(self, path: Path) -> None:
        super().__init__()
        self.path = path

    def execute(self, context: LaunchContext) -> None:
        context.entering(self.path)


class _LeaveFile(Action):
    def execute(self, context: LaunchContext) -> None:
        context.leaving()


class IncludeLaunchDescription(Action):
    """A Python source is read in place (its configurations scoped to it); an XML or YAML one is handed to
    hetros's importer with the scope it is included in."""

    def __init__(self, launch_description_source: Any, *, launch_arguments: Any = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        from .launch_description_sources import as_source

        self.launch_description_source = as_source(launch_description_source)
        self.launch_arguments = list(launch_arguments or [])

    def execute(self, context: LaunchContext) -> list[LaunchDescriptionEntity]:
        source = self.launch_description_source
        path = Path(source.location(context))
        if not path.is_absolute():
            path = context.current_launch_file.parent / path
        arguments = [(perform_substitutions(context, normalize_to_list_of_substitutions(k)),
                      perform_substitutions(context, normalize_to_list_of_substitutions(v)))
                     for k, v in self.launch_arguments]
        if not source.is_python(path):
            configurations = context.launch_configurations
            context.record("include", self.where, file=str(path.resolve()), args=dict(arguments),
                           namespace=configurations.get("ros_namespace", ""),
                           remap=list(configurations.get("ros_remaps", [])),
                           params=list(configurations.get("global_params", [])),
                           env=changed_environment(context))
            return []
        description = load_python_launch_file(path, self.where)
        return [PushLaunchConfigurations(), *(SetLaunchConfiguration(k, v) for k, v in arguments), _EnterFile(path),
                description, _LeaveFile(), PopLaunchConfigurations()]


def changed_environment(context: LaunchContext) -> dict[str, str]:
    """The variables the launch file set or changed: what a node's process gets beyond the launch's own."""
    return {k: v for k, v in context.environment.items() if os.environ.get(k) != v}


class ExecuteProcess(Action):
    """A process: hetros runs a package's own executable (``ExecutableInPackage``, ``ros2 run pkg exe``)
    as that node with its arguments, and refuses other programs naming the line."""

    def __init__(self, *, cmd: Iterable[Any], name: Any = None, cwd: Any = None, env: Any = None,
                 additional_env: Any = None, shell: bool = False, output: Any = "log", **kwargs: Any) -> None:
        kwargs = {k: v for k, v in kwargs.items() if k == "condition"}
        super().__init__(**kwargs)
        self.cmd = [normalize_to_list_of_substitutions(part) for part in cmd]
        self.name = name
        self.additional_env = dict(additional_env or {})
        self.shell = shell

    def execute(self, context: LaunchContext) -> None:
        if not self.cmd:
            raise LaunchFileError(f"{self.where}: ExecuteProcess needs a cmd")
        first = self.cmd[0]
        package_exe = getattr(first[0], "package_and_executable", None) if len(first) == 1 else None
        words = [perform_substitutions(context, part) for part in self.cmd[1:]]
        if package_exe is not None:
            package, executable = package_exe(context)
        else:
            program = perform_substitutions(context, first)
            package = executable = None
            if Path(program).name == "ros2" and len(words) >= 3 and words[0] == "run":
                package, executable, words = words[1], words[2], words[3:]
            else:
                words = [program, *words]
        env = changed_environment(context)
        env.update({perform_substitutions(context, normalize_to_list_of_substitutions(k)):
                    perform_substitutions(context, normalize_to_list_of_substitutions(v))
                    for k, v in self.additional_env.items()})
        name = None if self.name is None else perform_substitutions(context, normalize_to_list_of_substitutions(
            self.name))
        context.record("process", self.where, id=id(self), package=package, executable=executable, args=words,
                       name=name, env=env, shell=self.shell)


class OpaqueFunction(Action):
    def __init__(self, *, function: Callable[..., Any], args: Iterable[Any] | None = None,
                 kwargs: dict[str, Any] | None = None, **action_kwargs: Any) -> None:
        super().__init__(**action_kwargs)
        self.function = function
        self.args = list(args or [])
        self.kwargs = dict(kwargs or {})

    def execute(self, context: LaunchContext) -> list[LaunchDescriptionEntity]:
        return _entities(self.function(context, *self.args, **self.kwargs), self.where)


class TimerAction(Action):
    """Its actions start with the graph: hetros starts every node before any message flows (reliable topics
    keep what is published before a subscriber's first take), so a start delay orders nothing."""

    def __init__(self, *, period: Any, actions: Iterable[LaunchDescriptionEntity], cancel_on_shutdown: bool = True,
                 **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.period = normalize_to_list_of_substitutions(period)
        self.actions = _entities(actions, self.where)

    def get_sub_entities(self) -> list[LaunchDescriptionEntity]:
        return list(self.actions)

    def execute(self, context: LaunchContext) -> list[LaunchDescriptionEntity]:
        context.note(self.where, f"TimerAction(period={perform_substitutions(context, self.period)}): its actions "
                                 "start with the graph")
        return list(self.actions)


class RegisterEventHandler(Action):
    def __init__(self, event_handler: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.event_handler = event_handler

    def execute(self, context: LaunchContext) -> list[LaunchDescriptionEntity]:
        handle = getattr(self.event_handler, "entities_now", None)
        if handle is None:
            raise LaunchFileError(f"{self.where}: event handler {type(self.event_handler).__name__} has no "
                                  "counterpart in hetros; it knows OnProcessStart, OnProcessExit, "
                                  "OnExecutionComplete, OnShutdown and OnStateTransition")
        return list(handle(context, self.where))


class UnregisterEventHandler(Action):
    def __init__(self, event_handler: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)


class LogInfo(Action):
    def __init__(self, *, msg: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.msg = normalize_to_list_of_substitutions(msg)

    def execute(self, context: LaunchContext) -> None:
        context.record("log", self.where, text=perform_substitutions(context, self.msg))


class EmitEvent(Action):
    def __init__(self, *, event: Any, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.event = event

    def execute(self, context: LaunchContext) -> None:
        emitted = getattr(self.event, "emitted", None)
        if emitted is None:
            raise LaunchFileError(f"{self.where}: emitting {type(self.event).__name__} has no counterpart in hetros")
        emitted(context, self.where)


class Shutdown(Action):
    """At the top of a description: the launch ends as it starts (hetros notes it; a node's exit that
    shuts the launch down is ``required:``, see OnProcessExit)."""

    def __init__(self, *, reason: Any = "reason not given", **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.reason = reason

    def execute(self, context: LaunchContext) -> None:
        context.note(self.where, "Shutdown() outside an event handler: the launch would end at once; ignored")


__all__ = [
    "AppendEnvironmentVariable",
    "Condition",
    "DeclareLaunchArgument",
    "EmitEvent",
    "ExecuteProcess",
    "GroupAction",
    "IncludeLaunchDescription",
    "LogInfo",
    "OpaqueFunction",
    "PopEnvironment",
    "PopLaunchConfigurations",
    "PushEnvironment",
    "PushLaunchConfigurations",
    "RegisterEventHandler",
    "ResetEnvironment",
    "ResetLaunchConfigurations",
    "SetEnvironmentVariable",
    "SetLaunchConfiguration",
    "Shutdown",
    "TimerAction",
    "UnregisterEventHandler",
    "UnsetEnvironmentVariable",
    "UnsetLaunchConfiguration",
    "changed_environment",
    "load_python_launch_file",
]
