"""launch.conditions: whether an action is visited."""

from __future__ import annotations

from typing import Any

from ._core import Condition, LaunchContext, caller_place, normalize_to_list_of_substitutions, perform_substitutions
from .substitutions import truth


class IfCondition(Condition):
    def __init__(self, predicate_expression: Any) -> None:
        super().__init__()
        self.where = caller_place()
        self.predicate_expression = normalize_to_list_of_substitutions(predicate_expression)

    def evaluate(self, context: LaunchContext) -> bool:
        return truth(perform_substitutions(context, self.predicate_expression), self.where)


class UnlessCondition(IfCondition):
    def evaluate(self, context: LaunchContext) -> bool:
        return not super().evaluate(context)


class LaunchConfigurationEquals(Condition):
    def __init__(self, launch_configuration_name: str, expected_value: Any) -> None:
        super().__init__()
        self.name = launch_configuration_name
        self.expected = None if expected_value is None else normalize_to_list_of_substitutions(expected_value)

    def evaluate(self, context: LaunchContext) -> bool:
        expected = None if self.expected is None else perform_substitutions(context, self.expected)
        value = context.launch_configurations.get(self.name)
        return (None if value is None else str(value)) == expected


class LaunchConfigurationNotEquals(LaunchConfigurationEquals):
    def evaluate(self, context: LaunchContext) -> bool:
        return not super().evaluate(context)


__all__ = ["Condition", "IfCondition", "LaunchConfigurationEquals", "LaunchConfigurationNotEquals",
           "UnlessCondition"]
