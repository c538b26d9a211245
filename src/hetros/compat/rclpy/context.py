"""rclpy.context: the ``Context`` rclpy code passes around. A hetros node's context is its thread's
binding to its node: ``ok()`` until the node or the graph shuts down."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


class Context:
    def __init__(self) -> None:
        self._callbacks: list[Callable[[], None]] = []

    def init(self, args: list[str] | None = None, *, initialize_logging: bool = True,
             domain_id: int | None = None) -> None:
        from . import init

        init(args=args, domain_id=domain_id)

    def ok(self) -> bool:
        from . import ok

        return ok()

    def shutdown(self) -> None:
        from . import shutdown

        shutdown()
        for callback in self._callbacks:
            callback()

    def try_shutdown(self) -> None:
        self.shutdown()

    def on_shutdown(self, callback: Callable[[], None]) -> None:
        self._callbacks.append(callback)

    def __enter__(self) -> Context:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.try_shutdown()


__all__ = ["Context"]
