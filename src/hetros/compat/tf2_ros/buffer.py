"""tf2_ros.buffer: the transform tree a node looks transforms up in, waiting for them where asked.

A wait (``lookup_transform(..., timeout)``, ``can_transform``) ends when the transform can be looked
up, when the timeout passes, or when the graph stops; an asynchronous one (``wait_for_transform_async``,
``lookup_transform_async``) is an rclpy Future that a later ``set_transform`` completes."""

from __future__ import annotations

import threading
import time as _time
from collections.abc import Callable
from typing import Any

from ..._errors import Error
from ..rclpy.task import graph_stop
from ..tf2_py import BufferCore, to_ns
from .buffer_interface import BufferInterface


def _node_schedule() -> Callable[[Callable[[], None]], None] | None:
    """How a future's done-callbacks reach the calling node's executor (rclpy runs them there, between
    callbacks: a callback added under a lock the callback takes does not deadlock); None outside a node."""
    from ...runtime import bound_node

    try:
        executor = bound_node().executor
    except Error:
        return None
    return lambda work: executor.add_timer(_time.monotonic(), work)


class Buffer(BufferCore, BufferInterface):
    """tf2_ros.Buffer (ROS 1's and ROS 2's): ``Buffer(cache_time=None, node=None)``; ``node`` (ROS 2) and
    ``debug`` (ROS 1) change nothing here: the tree's frames are shown by ``hetros tf frames``."""

    def __init__(self, cache_time: Any = None, node: Any = None, debug: bool = True) -> None:
        BufferCore.__init__(self, cache_time)
        BufferInterface.__init__(self)
        self._changed = threading.Condition()
        self._new_data: list[Callable[[], None]] = []
        self.add_listener(self._on_new_data)

    def _on_new_data(self) -> None:
        with self._changed:
            self._changed.notify_all()
            pending = list(self._new_data)
        for callback in pending:
            callback()

    def _wait(self, ready: Callable[[], bool], timeout: Any) -> bool:
        """Whether ``ready()`` came true within ``timeout`` (ended early by the graph's stop)."""
        if ready():
            return True
        seconds = to_ns(timeout) / 1e9 if timeout is not None else 0.0
        if seconds <= 0:
            return False
        deadline = _time.monotonic() + seconds
        stop = graph_stop()
        with self._changed:
            while not ready():
                left = deadline - _time.monotonic()
                if left <= 0 or (stop is not None and stop.is_set()):
                    return False
                self._changed.wait(min(left, 0.1))
        return True

    # -- synchronous --------------------------------------------------------------------------

    def lookup_transform(self, target_frame: str, source_frame: str, time: Any, timeout: Any = None) -> Any:
        self.can_transform(target_frame, source_frame, time, timeout)
        return self.lookup_transform_core(target_frame, source_frame, time)

    def lookup_transform_full(self, target_frame: str, target_time: Any, source_frame: str, source_time: Any,
                              fixed_frame: str, timeout: Any = None) -> Any:
        self.can_transform_full(target_frame, target_time, source_frame, source_time, fixed_frame, timeout)
        return self.lookup_transform_full_core(target_frame, target_time, source_frame, source_time, fixed_frame)

    def can_transform(self, target_frame: str, source_frame: str, time: Any, timeout: Any = None,
                      return_debug_tuple: bool = False) -> Any:
        answer: list[tuple[bool, str]] = []

        def ready() -> bool:
            answer[:] = [self.can_transform_core(target_frame, source_frame, time)]
            return answer[0][0]
        self._wait(ready, timeout)
        return answer[0] if return_debug_tuple else answer[0][0]

    def can_transform_full(self, target_frame: str, target_time: Any, source_frame: str, source_time: Any,
                           fixed_frame: str, timeout: Any = None, return_debug_tuple: bool = False) -> Any:
        answer: list[tuple[bool, str]] = []

        def ready() -> bool:
            answer[:] = [self.can_transform_full_core(target_frame, target_time, source_frame, source_time,
                                                      fixed_frame)]
            return answer[0][0]
        self._wait(ready, timeout)
        return answer[0] if return_debug_tuple else answer[0][0]

    # -- asynchronous -------------------------------------------------------------------------

    def wait_for_transform_async(self, target_frame: str, source_frame: str, time: Any) -> Any:
        """A Future done with the transform once it can be looked up."""
        return self._future(lambda: self.can_transform_core(target_frame, source_frame, time)[0],
                            lambda: self.lookup_transform_core(target_frame, source_frame, time))

    def wait_for_transform_full_async(self, target_frame: str, target_time: Any, source_frame: str,
                                      source_time: Any, fixed_frame: str) -> Any:
        return self._future(
            lambda: self.can_transform_full_core(target_frame, target_time, source_frame, source_time,
                                                 fixed_frame)[0],
            lambda: self.lookup_transform_full_core(target_frame, target_time, source_frame, source_time,
                                                    fixed_frame))

    def _future(self, ready: Callable[[], bool], result: Callable[[], Any]) -> Any:
        from ..rclpy.task import Future

        future = Future(schedule=_node_schedule())
        if ready():
            future.set_result(result())
            return future

        def on_new_data() -> None:
            if future.done():
                return
            try:
                if ready():
                    future.set_result(result())
            except Exception as exc:  # a lookup's tf2 error ends the wait with that error
                future.set_exception(exc)

        def forget(_done: Any) -> None:
            with self._changed:
                if on_new_data in self._new_data:
                    self._new_data.remove(on_new_data)
        with self._changed:
            self._new_data.append(on_new_data)
        future.add_done_callback(forget)
        return future

    async def lookup_transform_async(self, target_frame: str, source_frame: str, time: Any) -> Any:
        await self.wait_for_transform_async(target_frame, source_frame, time)
        return self.lookup_transform_core(target_frame, source_frame, time)

    async def lookup_transform_full_async(self, target_frame: str, target_time: Any, source_frame: str,
                                          source_time: Any, fixed_frame: str) -> Any:
        await self.wait_for_transform_full_async(target_frame, target_time, source_frame, source_time, fixed_frame)
        return self.lookup_transform_full_core(target_frame, target_time, source_frame, source_time, fixed_frame)


__all__ = ["Buffer"]
