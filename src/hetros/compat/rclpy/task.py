"""rclpy.task.Future: a result that arrives later, completed by the node's executor."""

from __future__ import annotations

import threading
from collections.abc import Callable, Coroutine
from concurrent.futures import Future as _Concurrent
from typing import Any

from ..._errors import Error

# the Future a coroutine awaits, seen by the Task that stepped it (per thread: tasks step in their node's thread)
_awaited = threading.local()


def graph_stop() -> threading.Event | None:
    """The stop event of the graph this thread's node belongs to (None outside a node's thread)."""
    from ...runtime import bound_node

    try:
        return bound_node().graph.stop
    except Error:
        return None


class Future:
    """rclpy's Future: ``done()``, ``result()``, ``exception()``, ``add_done_callback``, ``cancel``."""

    def __init__(self, *, executor: Any = None, schedule: Callable[[Callable[[], None]], None] | None = None) -> None:
        self._schedule = schedule  # how done-callbacks reach the node's thread (rclpy runs them in its executor)
        self._lock = threading.Lock()
        self._done = False
        self._cancelled = False
        self._result: Any = None
        self._exception: BaseException | None = None
        self._callbacks: list[Callable[[Future], None]] = []
        self._finished = threading.Event()

    @classmethod
    def wrapping(cls, inner: _Concurrent[Any], convert: Callable[[Any], Any] = lambda value: value,
                 schedule: Callable[[Callable[[], None]], None] | None = None) -> Future:
        """An rclpy Future completed when ``inner`` (hetros's) is, through ``convert``."""
        future = cls(schedule=schedule)

        def finish(done: _Concurrent[Any]) -> None:
            if done.cancelled():
                future.cancel()
                return
            error = done.exception()
            if error is not None:
                future.set_exception(error)
                return
            try:
                future.set_result(convert(done.result()))
            except BaseException as exc:
                future.set_exception(exc)
        inner.add_done_callback(finish)
        return future

    def done(self) -> bool:
        return self._done

    def cancelled(self) -> bool:
        return self._cancelled

    def result(self) -> Any:
        if self._exception is not None:
            raise self._exception
        return self._result

    def exception(self) -> BaseException | None:
        return self._exception

    def set_result(self, result: Any) -> None:
        self._finish(result, None)

    def set_exception(self, exception: BaseException) -> None:
        self._finish(None, exception)

    def cancel(self) -> None:
        with self._lock:
            if self._done:
                return
            self._cancelled = True
        self._finish(None, None)

    def _finish(self, result: Any, exception: BaseException | None) -> None:
        with self._lock:
            if self._done:
                return
            self._result, self._exception, self._done = result, exception, True
            callbacks, self._callbacks = self._callbacks, []
        self._finished.set()
        for callback in callbacks:
            self._call(callback)

    def _call(self, callback: Callable[[Future], None]) -> None:
        if self._schedule is None:
            callback(self)
        else:
            self._schedule(lambda: callback(self))

    def add_done_callback(self, callback: Callable[[Future], None]) -> None:
        with self._lock:
            if not self._done:
                self._callbacks.append(callback)
                return
        self._call(callback)

    def wait(self, timeout: float | None = None) -> bool:
        return self._finished.wait(timeout)

    def __await__(self) -> Any:
        stop = graph_stop()
        while not self._done:
            if stop is not None and stop.is_set():
                from .executors import ExternalShutdownException

                # what Ctrl-C does to an rclpy program awaiting in asyncio's loop: the wait ends, and main()
                # can end (an endless yield would hold the process past the launch's end)
                raise ExternalShutdownException("the graph stopped while this future was awaited")
            _awaited.future = self  # the Task stepping the coroutine resumes it once this is done
            yield  # a bare yield, as rclpy's: asyncio's loop, driving the coroutine instead, steps it again soon
        return self.result()


class Task(Future):
    """A coroutine callback (``async def``) driven by the node's executor, as rclpy's executors drive them:
    stepped until it awaits a Future that is not done, stepped again once it is."""

    def __init__(self, coroutine: Coroutine[Any, Any, Any], schedule: Callable[[Callable[[], None]], None]) -> None:
        super().__init__(schedule=schedule)
        self._coroutine = coroutine
        self._resume = schedule

    def step(self) -> None:
        _awaited.future = None
        try:
            self._coroutine.send(None)
        except StopIteration as done:
            self.set_result(done.value)
            return
        except BaseException as exc:
            self.set_exception(exc)
            raise
        waited, _awaited.future = _awaited.future, None
        if isinstance(waited, Future) and not waited.done():
            waited.add_done_callback(lambda _future: self._resume(self.step))
        else:
            self._resume(self.step)


def run_to_end(coroutine: Coroutine[Any, Any, Any], stop: threading.Event) -> Any:
    """Drive ``coroutine`` in this thread until it returns (an ``async def`` execute callback runs so in its
    goal's thread): each awaited Future is waited for here."""
    while True:
        _awaited.future = None
        try:
            coroutine.send(None)
        except StopIteration as done:
            return done.value
        waited, _awaited.future = _awaited.future, None
        while isinstance(waited, Future) and not waited.wait(0.1):
            if stop.is_set():
                coroutine.close()
                from .executors import ExternalShutdownException

                raise ExternalShutdownException("the graph is shutting down")
