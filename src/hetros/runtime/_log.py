"""Node loggers: every line says which node wrote it."""

from __future__ import annotations

import logging
import sys

NODE_LOGGER_PREFIX = "hetros.node."


class NodeFormatter(logging.Formatter):
    """``[INFO] [listener]: I heard: hello 3`` (the shape ROS users know)."""

    def format(self, record: logging.LogRecord) -> str:
        name = record.name
        if name.startswith(NODE_LOGGER_PREFIX):
            name = name[len(NODE_LOGGER_PREFIX):]
        elif name.startswith("hetros."):
            name = name[len("hetros."):]
        text = f"[{record.levelname}] [{name}]: {record.getMessage()}"
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
