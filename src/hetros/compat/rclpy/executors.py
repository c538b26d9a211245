"""rclpy.executors on hetros: every rclpy node of a ``main()`` is a view of one hetros node, so an executor
spins that node's own executor (callbacks one at a time, in its thread); ``MultiThreadedExecutor`` runs
them one at a time as well."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from ..._errors import ShutdownError
from ...runtime import Node as HetrosNode
from ...runtime import bound_node as _bound_node
from ...runtime import shut_down as _shut_down
from .task import Future


class ExternalShutdownException(ShutdownError):
    """The graph stopped (Ctrl-C, the launch ended): what rclpy raises from ``spin`` when its context is shut
    down from outside. Uncaught, hetros reports the node as ended at shutdown."""


def _running(hetros: HetrosNode) -> bool:
    return not hetros.graph.stop.is_set() and not _shut_down()


def spin_node(hetros: HetrosNode, timeout_sec: float | None = None, ended: threading.Event | None = None) -> None:
    """Run callbacks until the graph stops (rclpy raises ExternalShutdownException then), ``rclpy.shutdown()``,
    ``timeout_sec``, or ``ended`` (an executor's ``shutdown()``)."""
    hetros.spun = True
    deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
    while _running(hetros) and not (ended is not None and ended.is_set()):
        left = None if deadline is None else deadline - time.monotonic()
        if left is not None and left <= 0:
            return
        hetros.executor.spin_once(0.1 if left is None else min(left, 0.1))
    if hetros.graph.stop.is_set() and not (ended is not None and ended.is_set()):
        raise ExternalShutdownException("the graph is shutting down")


def spin_once_node(hetros: HetrosNode, timeout_sec: float | None) -> None:
    """Wait for one piece of work and do it: a callback, or a reply or goal answer that arrived (hetros
    takes those without the callback queue, so a loop of ``spin_once`` and ``future.done()`` ends)."""
    hetros.spun = True
    if hetros.graph.stop.is_set():
        raise ExternalShutdownException("the graph is shutting down")
    executor = hetros.executor
    seen = executor.arrivals
    deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
    # the first turn takes the timeout as given: a ping-pong's reply comes within it, and arithmetic before the
    # executor starts polling would add to its round trip
    left = timeout_sec
    while _running(hetros):
        if left is not None and left <= 0:
            return
        # a wait that merely ended (each one moves the executor's generation) is no work done: a
        # `while cycles < 20: spin_once(node)` loop must count callbacks, not 20 ms waits
        if executor.spin_once(0.02 if left is None else min(left, 0.02)) or executor.arrivals != seen:
            return
        left = None if deadline is None else deadline - time.monotonic()


def spin_until_done(hetros: HetrosNode, future: Future, timeout_sec: float | None) -> None:
    hetros.spun = True
    deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
    while not future.done() and _running(hetros):
        left = None if deadline is None else deadline - time.monotonic()
        if left is not None and left <= 0:
            return
        hetros.executor.spin_once(0.05 if left is None else min(left, 0.05))
    if not future.done() and hetros.graph.stop.is_set():
        raise ExternalShutdownException("the graph is shutting down")


class Executor:
    def __init__(self, *, context: Any = None) -> None:
        self._nodes: list[Any] = []
        self._ended = threading.Event()  # shutdown(): spin returns

    def add_node(self, node: Any) -> bool:
        if node not in self._nodes:
            self._nodes.append(node)
            node.executor = self
        return True

    def remove_node(self, node: Any) -> None:
        if node in self._nodes:
            self._nodes.remove(node)

    def get_nodes(self) -> list[Any]:
        return list(self._nodes)

    def _hetros(self) -> HetrosNode:
        return self._nodes[0]._hetros if self._nodes else _bound_node()

    def spin(self) -> None:
        """Spin the node's executor; an executor class that overrides ``spin_once`` (a custom executor) has
        its own ``spin_once`` called in a loop, as rclpy's ``spin`` does."""
        hetros = self._hetros()
        if type(self).spin_once is Executor.spin_once:
            spin_node(hetros, ended=self._ended)
            return
        hetros.spun = True
        while _running(hetros) and not self._ended.is_set():
            self.spin_once(timeout_sec=0.1)
        if hetros.graph.stop.is_set() and not self._ended.is_set():
            raise ExternalShutdownException("the graph is shutting down")

    def spin_once(self, timeout_sec: float | None = None) -> None:
        spin_once_node(self._hetros(), timeout_sec)

    def wait_for_ready_callbacks(self, timeout_sec: float | None = None, nodes: Any = None,
                                 condition: Any = None) -> tuple[Callable[[], Any], Any, Any]:
        """The next ready callback as (handler, group, node), for a custom executor to run where it likes
        (``handler()``); its message is already taken. StopIteration when none came within ``timeout_sec``."""
        from .node import capturing

        hetros = self._hetros()
        ready: list[Any] = []
        deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
        capturing(ready)
        try:
            while not ready and _running(hetros):
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    break
                hetros.executor.spin_once(0.1 if left is None else min(left, 0.1))
        finally:
            capturing(None)
        if not ready:
            raise StopIteration
        handler, group, node = ready[0]
        for extra in ready[1:]:  # more than one came in one turn: run in order, here
            extra[0]()
        return handler, group, node

    def spin_until_future_complete(self, future: Future, timeout_sec: float | None = None) -> None:
        spin_until_done(self._hetros(), future, timeout_sec)

    def create_task(self, callback: Callable[..., Any], *args: Any) -> Future:
        future = Future()
        try:
            future.set_result(callback(*args))
        except Exception as exc:
            future.set_exception(exc)
        return future

    def shutdown(self, timeout_sec: float | None = None) -> bool:
        """End ``spin`` (in whichever thread runs it) within its next turn, as rclpy's does."""
        self._ended.set()
        if self._nodes:
            self._hetros().executor.wake()
        return True


class SingleThreadedExecutor(Executor):
    pass


class MultiThreadedExecutor(Executor):
    def __init__(self, num_threads: int | None = None, *, context: Any = None) -> None:
        super().__init__(context=context)
        self.num_threads = num_threads


class GuardCondition:
    """``node.create_guard_condition(callback)``: ``trigger()`` runs the callback in the node's executor."""

    def __init__(self, node: Any, callback: Callable[[], Any]) -> None:
        self._hetros: HetrosNode = node._hetros
        self.callback = callback

    def trigger(self) -> None:
        self._hetros.executor.add_timer(time.monotonic(), self._fire)

    def _fire(self) -> None:
        from .node import run_callback

        run_callback(self._hetros, self.callback)()

    def destroy(self) -> None:
        pass
