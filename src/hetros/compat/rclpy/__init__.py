"""rclpy, as hetros serves it to the nodes it runs (``hetros.compat``): ``init``, ``spin``, ``Node``, QoS,
services, actions and executors with rclpy's names and calling conventions, on the hetros node the
project wires. Outside hetros's processes ``import rclpy`` is ROS 2's own, if installed."""

from __future__ import annotations

from typing import Any

from ...runtime import bound_node as _bound_node
from ...runtime import mark_shut_down as _mark_shut_down
from ...runtime import shut_down as _shut_down
from . import clock, duration, time, timer  # noqa: F401  (rclpy's own import makes them attributes)
from .executors import (
    ExternalShutdownException,
    SingleThreadedExecutor,
    spin_node,
    spin_once_node,
    spin_until_done,
)
from .node import Node
from .task import Future


class _InitContext:
    """What ``rclpy.init()`` returns: usable as ``with rclpy.init():`` (shut down on leaving)."""

    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        try_shutdown()

    def ok(self) -> bool:
        return ok()


def init(*, args: list[str] | None = None, context: Any = None, domain_id: int | None = None,
         signal_handler_options: Any = None) -> _InitContext:
    """The node's context starts with its thread: nothing to set up; ``args`` are accepted and ignored (the
    project file holds parameters and names)."""
    _bound_node()
    _mark_shut_down(False)
    return _InitContext()


def shutdown(*, context: Any = None, uninstall_handlers: bool | None = None) -> None:
    """This node's context ends (``rclpy.ok()`` turns False, ``spin`` returns); the graph goes on."""
    _mark_shut_down(True)


def try_shutdown(*, context: Any = None, uninstall_handlers: bool | None = None) -> None:
    shutdown()


def ok(*, context: Any = None) -> bool:
    return not _shut_down() and not _bound_node().graph.stop.is_set()


def create_node(node_name: str, *, context: Any = None, cli_args: list[str] | None = None,
                namespace: str | None = None, **kwargs: Any) -> Node:
    return Node(node_name, context=context, cli_args=cli_args, namespace=namespace, **kwargs)


def spin(node: Node, executor: Any = None) -> None:
    spin_node(node._hetros)


def spin_once(node: Node, *, executor: Any = None, timeout_sec: float | None = None) -> None:
    spin_once_node(node._hetros, timeout_sec)


def spin_until_future_complete(node: Node, future: Future, executor: Any = None,
                               timeout_sec: float | None = None) -> None:
    spin_until_done(node._hetros, future, timeout_sec)


def get_global_executor() -> SingleThreadedExecutor:
    return SingleThreadedExecutor()


def get_default_context() -> Any:
    return None


__all__ = [
    "ExternalShutdownException",
    "Future",
    "Node",
    "create_node",
    "get_default_context",
    "get_global_executor",
    "init",
    "ok",
    "shutdown",
    "spin",
    "spin_once",
    "spin_until_future_complete",
    "try_shutdown",
]
