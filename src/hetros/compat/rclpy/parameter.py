"""rclpy.parameter: a parameter's name, value and type, as rclpy's ``Parameter``."""

from __future__ import annotations

import enum
from typing import Any


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


def _type_of(value: Any) -> ParameterType:
    if value is None:
        return ParameterType.NOT_SET
    if isinstance(value, bool):
        return ParameterType.BOOL
    if isinstance(value, int):
        return ParameterType.INTEGER
    if isinstance(value, float):
        return ParameterType.DOUBLE
    if isinstance(value, str):
        return ParameterType.STRING
    if isinstance(value, bytes):
        return ParameterType.BYTE_ARRAY
    if isinstance(value, list | tuple) and value:
        first = _type_of(value[0])
        return {ParameterType.BOOL: ParameterType.BOOL_ARRAY, ParameterType.INTEGER: ParameterType.INTEGER_ARRAY,
                ParameterType.DOUBLE: ParameterType.DOUBLE_ARRAY,
                ParameterType.STRING: ParameterType.STRING_ARRAY}.get(first, ParameterType.NOT_SET)
    return ParameterType.NOT_SET


class ParameterValue:
    """``get_parameter_value()``: the value in the field of its type."""

    def __init__(self, value: Any) -> None:
        self.type = int(_type_of(value))
        self.bool_value = value if isinstance(value, bool) else False
        self.integer_value = value if isinstance(value, int) and not isinstance(value, bool) else 0
        self.double_value = float(value) if isinstance(value, float) else 0.0
        self.string_value = value if isinstance(value, str) else ""
        self.byte_array_value = value if isinstance(value, bytes) else b""
        items = list(value) if isinstance(value, list | tuple) else []
        self.bool_array_value = items if self.type == ParameterType.BOOL_ARRAY else []
        self.integer_array_value = items if self.type == ParameterType.INTEGER_ARRAY else []
        self.double_array_value = items if self.type == ParameterType.DOUBLE_ARRAY else []
        self.string_array_value = items if self.type == ParameterType.STRING_ARRAY else []


class Parameter:
    Type = ParameterType

    def __init__(self, name: str, type_: ParameterType | None = None, value: Any = None) -> None:
        self.name = name
        self.value = value
        self.type_ = ParameterType(type_) if type_ is not None else _type_of(value)

    def get_parameter_value(self) -> ParameterValue:
        return ParameterValue(self.value)

    def __repr__(self) -> str:
        return f"Parameter(name={self.name!r}, value={self.value!r})"
