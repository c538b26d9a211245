"""launch_ros.descriptions: parameter values and files, and composable nodes."""

from __future__ import annotations

from typing import Any

from ..launch._core import caller_place


class ParameterValue:
    """A parameter's value, with the type it is read as (``value_type=str`` keeps a substitution's text)."""

    def __init__(self, value: Any, *, value_type: Any = None) -> None:
        self.value = value
        self.value_type = value_type


class ParameterFile:
    def __init__(self, param_file: Any, *, allow_substs: Any = False) -> None:
        self.param_file = param_file
        self.allow_substs = allow_substs


class Parameter:
    def __init__(self, name: Any, value: Any, *, value_type: Any = None) -> None:
        self.name = name
        self.value = ParameterValue(value, value_type=value_type)


class ComposableNode:
    def __init__(self, *, package: Any, plugin: Any, name: Any = None, namespace: Any = None,
                 parameters: Any = None, remappings: Any = None, extra_arguments: Any = None,
                 condition: Any = None) -> None:
        self.where = caller_place()
        self.package = package
        self.plugin = plugin
        self.name = name
        self.namespace = namespace
        self.parameters = parameters
        self.remappings = remappings
        self.extra_arguments = extra_arguments
        self.condition = condition


__all__ = ["ComposableNode", "Parameter", "ParameterFile", "ParameterValue"]
