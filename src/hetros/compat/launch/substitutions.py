"""launch.substitutions: the strings a launch file computes when it runs."""

from __future__ import annotations

import math
import os
import shutil
import uuid
from pathlib import Path
from typing import Any

from ._core import (
    LaunchContext,
    LaunchFileError,
    Substitution,
    TextSubstitution,
    normalize_to_list_of_substitutions,
    perform_substitutions,
)

_TRUE = ("true", "1")
_FALSE = ("false", "0")


def truth(text: str, where: str) -> bool:
    """A performed condition or boolean substitution, as launch reads it."""
    value = text.strip().lower()
    if value in _TRUE:
        return True
    if value in _FALSE:
        return False
    raise LaunchFileError(f"{where}: {text!r} must be true, false, 1 or 0")


class LaunchConfiguration(Substitution):
    def __init__(self, variable_name: Any, *, default: Any = None) -> None:
        super().__init__()
        self.variable_name = normalize_to_list_of_substitutions(variable_name)
        self.default = None if default is None else normalize_to_list_of_substitutions(default)

    def perform(self, context: LaunchContext) -> str:
        name = perform_substitutions(context, self.variable_name)
        if name in context.launch_configurations:
            return str(context.launch_configurations[name])
        if self.default is not None:
            return perform_substitutions(context, self.default)
        raise LaunchFileError(f"{self.where}: launch configuration {name!r} does not exist; declare it with "
                          f"DeclareLaunchArgument({name!r}, default_value=...) or pass {name}:=VALUE")

    def describe(self) -> str:
        return f"LaunchConfiguration({''.join(s.describe() for s in self.variable_name)})"


class EnvironmentVariable(Substitution):
    def __init__(self, name: Any, *, default_value: Any = None) -> None:
        super().__init__()
        self.name = normalize_to_list_of_substitutions(name)
        self.default_value = None if default_value is None else normalize_to_list_of_substitutions(default_value)

    def perform(self, context: LaunchContext) -> str:
        name = perform_substitutions(context, self.name)
        if name in context.environment:
            return context.environment[name]
        if self.default_value is not None:
            return perform_substitutions(context, self.default_value)
        raise LaunchFileError(f"{self.where}: environment variable {name!r} is not set; set it or give default_value=")


class PathJoinSubstitution(Substitution):
    def __init__(self, substitutions: Any) -> None:
        super().__init__()
        self.substitutions = [normalize_to_list_of_substitutions(part) for part in substitutions]

    def perform(self, context: LaunchContext) -> str:
        return os.path.join(*(perform_substitutions(context, part) for part in self.substitutions))

    def __truediv__(self, other: Any) -> PathJoinSubstitution:
        joined = PathJoinSubstitution([])
        joined.substitutions = [*self.substitutions, normalize_to_list_of_substitutions(other)]
        return joined


class PythonExpression(Substitution):
    """The expression evaluated as launch does, with the ``math`` module's names at hand (and, as launch
    allows, modules named in ``python_modules``)."""

    def __init__(self, expression: Any, python_modules: Any = ("math",)) -> None:
        super().__init__()
        self.expression = normalize_to_list_of_substitutions(expression)
        self.python_modules = [normalize_to_list_of_substitutions(m) for m in python_modules]

    def perform(self, context: LaunchContext) -> str:
        import importlib

        expression = perform_substitutions(context, self.expression)
        names: dict[str, Any] = {}
        for module_subs in self.python_modules:
            module_name = perform_substitutions(context, module_subs)
            module = importlib.import_module(module_name)
            names[module_name] = module
            if module is math:
                names.update({k: v for k, v in vars(math).items() if not k.startswith("_")})
        try:
            return str(eval(expression, names))
        except Exception as exc:
            raise LaunchFileError(f"{self.where}: PythonExpression {expression!r} failed: {exc}") from None


class FindExecutable(Substitution):
    def __init__(self, *, name: Any) -> None:
        super().__init__()
        self.name = normalize_to_list_of_substitutions(name)

    def perform(self, context: LaunchContext) -> str:
        name = perform_substitutions(context, self.name)
        found = shutil.which(name, path=context.environment.get("PATH"))
        if found is None:
            raise LaunchFileError(f"{self.where}: executable {name!r} not found on PATH")
        return found


class ThisLaunchFileDir(Substitution):
    def perform(self, context: LaunchContext) -> str:
        return str(context.current_launch_file.parent)


class ThisLaunchFile(Substitution):
    def perform(self, context: LaunchContext) -> str:
        return str(context.current_launch_file)


_ANONYMOUS: dict[str, str] = {}  # one launch is one evaluating process


class AnonName(Substitution):
    """``name`` made unique once per launch, as launch's anonymous names are."""

    def __init__(self, name: Any) -> None:
        super().__init__()
        self.name = normalize_to_list_of_substitutions(name)

    def perform(self, context: LaunchContext) -> str:
        name = perform_substitutions(context, self.name)
        return _ANONYMOUS.setdefault(name, f"{name}_{uuid.uuid4().hex[:12]}")


class Command(Substitution):
    """A program's output, run while the description is read: hetros refuses it, since the graph must
    be known without running anything but the launch file itself."""

    def __init__(self, command: Any, *, on_stderr: Any = "fail") -> None:
        super().__init__()
        self.command = normalize_to_list_of_substitutions(command)

    def perform(self, context: LaunchContext) -> str:
        raise LaunchFileError(f"{self.where}: Command(...) runs a program while the launch is read, which hetros does "
                          "not do; write its output to a file and read it with a parameter file")


class NotSubstitution(Substitution):
    def __init__(self, value: Any) -> None:
        super().__init__()
        self.value = normalize_to_list_of_substitutions(value)

    def perform(self, context: LaunchContext) -> str:
        return str(not truth(perform_substitutions(context, self.value), self.where)).lower()


class _Binary(Substitution):
    def __init__(self, left: Any, right: Any) -> None:
        super().__init__()
        self.left = normalize_to_list_of_substitutions(left)
        self.right = normalize_to_list_of_substitutions(right)

    def values(self, context: LaunchContext) -> tuple[bool, bool]:
        return (truth(perform_substitutions(context, self.left), self.where),
                truth(perform_substitutions(context, self.right), self.where))


class AndSubstitution(_Binary):
    def perform(self, context: LaunchContext) -> str:
        left, right = self.values(context)
        return str(left and right).lower()


class OrSubstitution(_Binary):
    def perform(self, context: LaunchContext) -> str:
        left, right = self.values(context)
        return str(left or right).lower()


class EqualsSubstitution(_Binary):
    def perform(self, context: LaunchContext) -> str:
        return str(perform_substitutions(context, self.left) == perform_substitutions(context, self.right)).lower()


class NotEqualsSubstitution(EqualsSubstitution):
    def perform(self, context: LaunchContext) -> str:
        return str(super().perform(context) == "false").lower()


class IfElseSubstitution(Substitution):
    def __init__(self, condition: Any, if_value: Any = "", else_value: Any = "") -> None:
        super().__init__()
        self.condition = normalize_to_list_of_substitutions(condition)
        self.if_value = normalize_to_list_of_substitutions(if_value)
        self.else_value = normalize_to_list_of_substitutions(else_value)

    def perform(self, context: LaunchContext) -> str:
        chosen = self.if_value if truth(perform_substitutions(context, self.condition), self.where) else \
            self.else_value
        return perform_substitutions(context, chosen)


class FileContent(Substitution):
    def __init__(self, path: Any) -> None:
        super().__init__()
        self.path = normalize_to_list_of_substitutions(path)

    def perform(self, context: LaunchContext) -> str:
        path = Path(perform_substitutions(context, self.path))
        try:
            return path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise LaunchFileError(f"{self.where}: FileContent({str(path)!r}): {exc}") from None


class LaunchLogDir(Substitution):
    def perform(self, context: LaunchContext) -> str:
        return str(Path(context.environment.get("ROS_LOG_DIR", Path.home() / ".ros" / "log")))


__all__ = [
    "AndSubstitution",
    "AnonName",
    "Command",
    "EnvironmentVariable",
    "EqualsSubstitution",
    "FileContent",
    "FindExecutable",
    "IfElseSubstitution",
    "LaunchConfiguration",
    "LaunchLogDir",
    "NotEqualsSubstitution",
    "NotSubstitution",
    "OrSubstitution",
    "PathJoinSubstitution",
    "PythonExpression",
    "Substitution",
    "TextSubstitution",
    "ThisLaunchFile",
    "ThisLaunchFileDir",
    "truth",
]
