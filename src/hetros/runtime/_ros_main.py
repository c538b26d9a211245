"""Which hetros node a ROS ``main()`` runs as: bound to the node's thread while hetros runs it.

A ``run:`` target that takes no argument (``def main(args=None)``, the entry point of an rclpy
node) is called with its hetros node bound to the thread; ``hetros.compat``'s rclpy finds it
there (:func:`bound_node`).
"""

from __future__ import annotations

import inspect
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from .._errors import NodeError
from ._node import Node

_bound = threading.local()


def runs_as_ros_main(factory: Callable[..., Any]) -> bool:
    """A ``run:`` target written for ROS (``def main(args=None)``): a function, not a class, that takes no
    required argument; hetros node functions take the node."""
    if inspect.isclass(factory) or not callable(factory):
        return False
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):
        return False
    return not any(p.default is inspect.Parameter.empty and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
                   for p in signature.parameters.values())


@contextmanager
def ros_main(node: Node) -> Iterator[None]:
    """Bind ``node`` to this thread while a ROS ``main()`` runs in it."""
    previous = getattr(_bound, "node", None)
    _bound.node = node
    _bound.shut_down = False
    try:
        yield
    finally:
        _bound.node = previous


def bound_node() -> Node:
    """The hetros node this thread runs as (inside ``ros_main``); NodeError outside hetros."""
    node: Node | None = getattr(_bound, "node", None)
    if node is None:
        raise NodeError("this rclpy is hetros's: it runs inside `hetros launch` only, as the main() of a node the "
                        "project names (run: package.module:main); outside hetros, use ROS 2's own rclpy")
    return node


def shut_down() -> bool:
    """Whether this thread's ROS code called ``rclpy.shutdown()`` (its own context, not the graph)."""
    return bool(getattr(_bound, "shut_down", False))


def mark_shut_down(value: bool = True) -> None:
    _bound.shut_down = value
