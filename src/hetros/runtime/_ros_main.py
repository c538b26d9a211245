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
# the nodes running a ROS main() in this process, and the threads of their own that their code started
_mains: dict[int, Node] = {}
_threads: dict[int, Node] = {}
_lock = threading.Lock()
_hooked: list[Callable[[threading.ExceptHookArgs], Any]] = []


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
    _watch_threads()
    with _lock:
        _mains[id(node)] = node
    try:
        yield
    finally:
        _bound.node = previous
        with _lock:
            _mains.pop(id(node), None)


def bound_node() -> Node:
    """The hetros node this thread runs as (inside ``ros_main``); NodeError outside hetros."""
    node: Node | None = getattr(_bound, "node", None)
    if node is None:
        node = _node_of_this_process()
        _bound.node = node  # a thread the node's code started: it is that node's from now on
        _bound.shut_down = False
        with _lock:
            _threads[threading.get_ident()] = node
    return node


def _node_of_this_process() -> Node:
    """The node a thread the user's code started belongs to: the one node of this process running a ROS
    main(); with several, which one is not known, and with none this is not a hetros process."""
    with _lock:
        mains = list(_mains.values())
    if len(mains) == 1:
        return mains[0]
    if not mains:
        raise NodeError("this rclpy is hetros's: it runs inside `hetros launch` only, as the main() of a node the "
                        "project names (run: package.module:main); outside hetros, use ROS 2's own rclpy")
    raise NodeError(f"a thread of its own asks for its node, in a process running {len(mains)} ROS nodes "
                    f"({', '.join(sorted(n.name for n in mains))}): hetros cannot tell which one's it is; give that "
                    "node a process target of its own (kind: process), or make the node in its main thread")


def _watch_threads() -> None:
    """A thread that a node's code started and that raises fails that node (``Node.thread_failure``): the
    launcher reports it when the node's main returns, instead of the node going quiet."""
    with _lock:
        if _hooked:
            return
        _hooked.append(threading.excepthook)

    def hook(args: threading.ExceptHookArgs) -> None:
        with _lock:
            ident = args.thread.ident if args.thread is not None else None
            node = _threads.get(ident) if ident is not None else None
        if node is None or args.exc_type is SystemExit:
            _hooked[0](args)
            return
        import traceback

        node.thread_failure = "".join(traceback.format_exception(args.exc_type, args.exc_value, args.exc_traceback))
        node.log.error(f"thread {args.thread.name if args.thread else '?'} of node {node.name} raised:\n"
                       f"{node.thread_failure}")
    threading.excepthook = hook


def shut_down() -> bool:
    """Whether this thread's ROS code called ``rclpy.shutdown()`` (its own context, not the graph)."""
    return bool(getattr(_bound, "shut_down", False))


def mark_shut_down(value: bool = True) -> None:
    _bound.shut_down = value
