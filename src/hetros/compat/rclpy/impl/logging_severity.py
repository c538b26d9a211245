"""rclpy.impl.logging_severity: the severities of rcutils' loggers."""

from ..logging import LoggingSeverity

__all__ = ["LoggingSeverity"]
