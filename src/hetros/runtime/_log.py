"""Node loggers: every line says which node wrote it."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

NODE_LOGGER_PREFIX = "hetros.node."


# ROS's severity names where Python's differ
_SEVERITY = {"WARNING": "WARN", "CRITICAL": "FATAL"}


# a record's ``ros_console`` (``extra=``): the console form of the ROS client library the node is written for
RCLPY_CONSOLE = {"ros_console": "rclpy"}
ROSPY_CONSOLE = {"ros_console": "rospy"}


class NodeFormatter(logging.Formatter):
    """``[INFO] [listener]: I heard: hello 3`` (the shape ROS users know); a node written for rclpy gets
    ROS 2's ``[INFO] [1795662970.538698702] [listener]: ...`` and one written for rospy ROS 1's
    ``[INFO] [1795662970.538698]: ...``, as they would print under ROS."""

    stamped = False  # every line with its wall time and node, whatever its form (log files)

    def format(self, record: logging.LogRecord) -> str:
        name = record.name
        if name.startswith(NODE_LOGGER_PREFIX):
            name = name[len(NODE_LOGGER_PREFIX):]
        elif name.startswith("hetros."):
            name = name[len("hetros."):]
        severity = f"[{_SEVERITY.get(record.levelname, record.levelname)}]"
        console = getattr(record, "ros_console", "")
        if self.stamped or console == "rclpy":
            head = f"{severity} [{record.created:.9f}] [{name}]"
        elif console == "rospy":
            head = f"{severity} [{record.created:.6f}]"
        else:
            head = f"{severity} [{name}]"
        text = f"{head}: {record.getMessage()}"
        if record.exc_info:
            text += "\n" + self.formatException(record.exc_info)
        return text


def node_logger(name: str) -> logging.Logger:
    return logging.getLogger(NODE_LOGGER_PREFIX + name)


def setup_logging(level: int = logging.INFO) -> None:
    """Send hetros logs to stderr, one line per record, flushed at once."""
    root = logging.getLogger("hetros")
    if any(getattr(h, "_hetros", False) for h in root.handlers):
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(NodeFormatter())
    handler._hetros = True  # type: ignore[attr-defined]
    root.addHandler(handler)
    root.setLevel(level)
    root.propagate = False


class StampedFormatter(NodeFormatter):
    """``[INFO] [1795662970.538698702] [listener]: I heard: hello 3``: ROS 2's console format, with the
    wall time that lets ``hetros log`` merge the lines of every process of a launch."""

    stamped = True


def log_to_file(path: Path) -> logging.Handler:
    """Also write this process' hetros log lines to ``path`` (created readable by this user only),
    until the handler returned is removed (``stop_logging_to``)."""
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    handler = logging.StreamHandler(os.fdopen(descriptor, "a", buffering=1, encoding="utf-8"))
    handler.setFormatter(StampedFormatter())
    logging.getLogger("hetros").addHandler(handler)
    return handler


def stop_logging_to(handler: logging.Handler) -> None:
    logging.getLogger("hetros").removeHandler(handler)
    handler.close()
