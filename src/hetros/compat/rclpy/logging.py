"""rclpy.logging: a node's logger as rclpy's (``info``, ``warn``, ``once=``, ``throttle_duration_sec=``),
writing through hetros's node loggers (one line per record, `hetros log`, /rosout)."""

from __future__ import annotations

import enum
import logging as _logging
import time
from typing import Any

from ...runtime import RCLPY_CONSOLE, node_logger


class LoggingSeverity(enum.IntEnum):
    UNSET = 0
    DEBUG = 10
    INFO = 20
    WARN = 30
    ERROR = 40
    FATAL = 50


class RcutilsLogger:
    def __init__(self, name: str) -> None:
        self.name = name
        self._logger = node_logger(name)
        self._seen: dict[tuple[str, str], float] = {}
        self._skipped: set[tuple[str, str]] = set()

    def get_child(self, name: str) -> RcutilsLogger:
        return RcutilsLogger(f"{self.name}.{name}")

    def set_level(self, level: LoggingSeverity | int) -> None:
        self._logger.setLevel(int(level))

    def get_effective_level(self) -> LoggingSeverity:
        return LoggingSeverity(self._logger.getEffectiveLevel())

    def is_enabled_for(self, severity: LoggingSeverity | int) -> bool:
        return self._logger.isEnabledFor(int(severity))

    def log(self, message: Any, severity: LoggingSeverity | int, *, once: bool = False,
            throttle_duration_sec: float | None = None, skip_first: bool = False, **_ignored: Any) -> bool:
        key = (str(message) if once or skip_first else "", f"{int(severity)}")
        if once or throttle_duration_sec is not None or skip_first:
            now = time.monotonic()
            if skip_first and key not in self._skipped:
                self._skipped.add(key)
                return False
            last = self._seen.get(key)
            if last is not None and (once or now - last < float(throttle_duration_sec or 0)):
                return False
            self._seen[key] = now
        level = _logging.CRITICAL if int(severity) >= LoggingSeverity.FATAL else int(severity)
        self._logger.log(level, "%s", message, extra=RCLPY_CONSOLE)
        return True

    def debug(self, message: Any, **kwargs: Any) -> bool:
        return self.log(message, LoggingSeverity.DEBUG, **kwargs)

    def info(self, message: Any, **kwargs: Any) -> bool:
        return self.log(message, LoggingSeverity.INFO, **kwargs)

    def warning(self, message: Any, **kwargs: Any) -> bool:
        return self.log(message, LoggingSeverity.WARN, **kwargs)

    warn = warning

    def error(self, message: Any, **kwargs: Any) -> bool:
        return self.log(message, LoggingSeverity.ERROR, **kwargs)

    def fatal(self, message: Any, **kwargs: Any) -> bool:
        return self.log(message, LoggingSeverity.FATAL, **kwargs)


def get_logger(name: str) -> RcutilsLogger:
    return RcutilsLogger(name)


def get_logger_level(name: str) -> LoggingSeverity:
    """The level set on logger ``name`` itself (``UNSET`` where it follows its parent)."""
    return LoggingSeverity(node_logger(name).level)


def set_logger_level(name: str, level: LoggingSeverity | int) -> None:
    """Set logger ``name``'s level; a level rcutils does not have is refused, as rclpy refuses it."""
    try:
        severity = LoggingSeverity(int(level))
    except ValueError:
        raise ValueError(f"level must be one of {[int(s) for s in LoggingSeverity]}, not {level!r}") from None
    node_logger(name).setLevel(int(severity))


def get_logging_severity_from_string(log_severity: str) -> LoggingSeverity:
    return LoggingSeverity[log_severity.upper()]
