"""rclpy.parameter: a parameter's name, value and type, as rclpy's ``Parameter``, and the helpers rclpy code
uses beside it (``parameter_value_to_python``, ``parameter_dict_from_yaml_file``). Messages are the real
``rcl_interfaces`` ones, so that a parameter goes into a service request as it is."""

from __future__ import annotations

import enum
from typing import Any

import yaml

from ..._errors import ParameterError
from ...runtime import from_value_message, kind_of, to_value_message

# rclpy's PARAMETER_SEPARATOR_STRING: nested names (``camera.width``)
PARAMETER_SEPARATOR_STRING = "."


class ParameterType(enum.IntEnum):
    NOT_SET = 0
    BOOL = 1
    INTEGER = 2
    DOUBLE = 3
    STRING = 4
    BYTE_ARRAY = 5
    BOOL_ARRAY = 6
    INTEGER_ARRAY = 7
    DOUBLE_ARRAY = 8
    STRING_ARRAY = 9

    @classmethod
    def from_parameter_value(cls, parameter_value: Any) -> ParameterType:
        return cls(kind_of(parameter_value))


class Parameter:
    Type = ParameterType

    def __init__(self, name: str, type_: ParameterType | None = None, value: Any = None) -> None:
        self.name = name
        self.value = value
        self.type_ = ParameterType(type_) if type_ is not None else ParameterType(kind_of(value))

    @classmethod
    def from_parameter_msg(cls, param_msg: Any) -> Parameter:
        return cls(param_msg.name, ParameterType(int(param_msg.value.type)), from_value_message(param_msg.value))

    def get_parameter_value(self) -> Any:
        """The rcl_interfaces/msg/ParameterValue holding this parameter's value."""
        return to_value_message(self.value)

    def to_parameter_msg(self) -> Any:
        from ...interfaces.rcl_interfaces.msg import Parameter as ParameterMessage

        return ParameterMessage(name=self.name, value=self.get_parameter_value())

    def __repr__(self) -> str:
        return f"Parameter(name={self.name!r}, value={self.value!r})"


def parameter_value_to_python(parameter_value: Any) -> Any:
    """The Python value an rcl_interfaces/msg/ParameterValue holds (None when NOT_SET)."""
    return from_value_message(parameter_value)


def get_parameter_value(string_value: str) -> Any:
    """rclpy's guess of a parameter's type from text (YAML's reading of it), as a ParameterValue."""
    try:
        value = yaml.safe_load(string_value)
    except yaml.YAMLError:
        value = string_value
    if kind_of(value) == ParameterType.NOT_SET:
        value = string_value
    return to_value_message(value)


def parameter_dict_from_yaml_file(parameter_file: str, use_wildcard: bool = False,
                                  target_nodes: list[str] | None = None, namespace: str = "") -> dict[str, Any]:
    """rcl_interfaces/msg/Parameter messages by name from a ROS 2 parameter file: every node's section
    (``/**`` first, when ``use_wildcard``), or only ``target_nodes``'; nested names joined with dots."""
    with open(parameter_file, encoding="utf-8") as file:
        loaded = yaml.safe_load(file)
    if not isinstance(loaded, dict):
        raise ParameterError(f"{parameter_file}: not a ROS 2 parameter file (a mapping of node names to "
                             "{ros__parameters: ...})")
    keys = ["/**"] if use_wildcard and "/**" in loaded else []
    if target_nodes:
        for node in target_nodes:
            if node not in loaded:
                raise ParameterError(f"{parameter_file}: no parameters for {node} (it has: {list(loaded)})")
            keys.append(node)
    else:
        keys += [key for key in loaded if key != "/**"]
    if not keys:
        raise ParameterError(f"{parameter_file}: no parameters for the nodes asked")
    flat: dict[str, Any] = {}
    for key in keys:
        section = loaded[key]
        if not isinstance(section, dict) or "ros__parameters" not in section:
            raise ParameterError(f"{parameter_file}: {key} has no ros__parameters: not a ROS 2 parameter file")
        flat.update(section["ros__parameters"])
    return _flattened(namespace, flat)


def _flattened(prefix: str, values: dict[str, Any]) -> dict[str, Any]:
    found: dict[str, Any] = {}
    for name, value in values.items():
        full = prefix + str(name)
        if isinstance(value, dict):
            found.update(_flattened(full + PARAMETER_SEPARATOR_STRING, value))
        else:
            found[full] = Parameter(full, value=value).to_parameter_msg()
    return found
