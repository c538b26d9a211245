"""rclpy.exceptions: the parameter errors rclpy code catches, in hetros's error tree."""

from __future__ import annotations

from typing import Any

from ..._errors import ParameterError


class ParameterNotDeclaredException(ParameterError):
    def __init__(self, parameters: Any) -> None:
        super().__init__(f"parameter(s) not declared: {parameters}; call declare_parameter first")
        self.parameters = parameters


class InvalidParameterValueException(ParameterError):
    def __init__(self, parameter: str, value: Any, reason: str) -> None:
        super().__init__(f"invalid value {value!r} for parameter {parameter!r}: {reason}")
        self.parameter, self.value, self.reason = parameter, value, reason


class ParameterAlreadyDeclaredException(ParameterError):
    def __init__(self, parameters: Any) -> None:
        super().__init__(f"parameter(s) already declared: {parameters}")
        self.parameters = parameters


__all__ = ["InvalidParameterValueException", "ParameterAlreadyDeclaredException", "ParameterNotDeclaredException"]
