"""rclpy.task.Future: a result that arrives later, completed by the node's executor."""

from __future__ import annotations

import threading
from collections.abc import Callable, Coroutine
from concurrent.futures import Future as _Concurrent
from typing import Any


class Future:
    """rclpy's Future: ``done()``, ``result()``, ``exception()``, ``add_done_callback``, ``cancel``."""

    def __init__(self, *, executor: Any = None) -> None:
        self._lock = threading.Lock()
        self._done = False
        self._cancelled = False
        self._result: Any = None
        self._exception: BaseException | None = None
        self._callbacks: list[Callable[[Future], None]] = []
        self._finished = threading.Event()

    @classmethod
    def wrapping(cls, inner: _Concurrent[Any], convert: Callable[[Any], Any] = lambda value: value) -> Future:
        """An rclpy Future completed when ``inner`` (hetros's) is, through ``convert``."""
        future = cls()

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
            callback(self)

    def add_done_callback(self, callback: Callable[[Future], None]) -> None:
        with self._lock:
            if not self._done:
                self._callbacks.append(callback)
                return
        callback(self)

    def wait(self, timeout: float | None = None) -> bool:
        return self._finished.wait(timeout)

    def __await__(self) -> Any:
        while not self._done:
            yield self  # the task driving the awaiting coroutine steps it again once this is done
        return self.result()


class Task(Future):
    """A coroutine callback (``async def``) driven by the node's executor, as rclpy's executors drive them:
    stepped until it awaits a Future that is not done, stepped again once it is."""

    def __init__(self, coroutine: Coroutine[Any, Any, Any], schedule: Callable[[Callable[[], None]], None]) -> None:
        super().__init__()
        self._coroutine = coroutine
        self._schedule = schedule

    def step(self) -> None:
        try:
            waited = self._coroutine.send(None)
        except StopIteration as done:
            self.set_result(done.value)
            return
        except BaseException as exc:
            self.set_exception(exc)
            raise
        if isinstance(waited, Future) and not waited.done():
            waited.add_done_callback(lambda _future: self._schedule(self.step))
        else:
            self._schedule(self.step)
