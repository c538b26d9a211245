"""rclpy.action.server on hetros's action server: rclpy's callbacks (goal, handle_accepted, cancel, execute)
and goal handle, with rclpy's defaults (accept every goal, execute it at once, refuse every cancel)."""

from __future__ import annotations

import enum
import inspect
import threading
from collections.abc import Callable
from typing import Any

from ...._log import get_logger
from ....runtime import ActionServer as HetrosActionServer
from ....runtime import ServerGoalHandle as HetrosGoalHandle
from ....runtime import uuid_message
from ..._flavour import copied, received
from ..task import run_to_end

log = get_logger("rclpy.action")


class GoalResponse(enum.IntEnum):
    REJECT = 1
    ACCEPT = 2


class CancelResponse(enum.IntEnum):
    REJECT = 1
    ACCEPT = 2


def default_goal_callback(goal_request: Any) -> GoalResponse:
    return GoalResponse.ACCEPT


def default_handle_accepted_callback(goal_handle: ServerGoalHandle) -> None:
    goal_handle.execute()


def default_cancel_callback(cancel_request: Any) -> CancelResponse:
    return CancelResponse.REJECT


class ServerGoalHandle:
    """rclpy's goal handle: ``request``, ``execute()``, feedback, and the calls that end the goal."""

    def __init__(self, inner: HetrosGoalHandle, action_type: Any) -> None:
        self._inner = inner
        self._type = action_type
        self.request = received(inner.request)
        self._executing = threading.Event()

    @property
    def goal_id(self) -> Any:
        return uuid_message(self._inner.goal_id)

    @property
    def is_active(self) -> bool:
        return self._inner.is_active

    @property
    def is_cancel_requested(self) -> bool:
        return self._inner.is_cancel_requested

    @property
    def status(self) -> int:
        return int(self._inner.status)

    def execute(self, execute_callback: Callable[..., Any] | None = None) -> None:
        """Start executing (the goal's thread waits for this when ``handle_accepted_callback`` defers)."""
        self._executing.set()

    def publish_feedback(self, feedback: Any) -> None:
        self._inner.publish_feedback(copied(feedback, self._type.Feedback, "the feedback of a goal"))

    def succeed(self) -> None:
        self._inner.succeed()

    def abort(self) -> None:
        self._inner.abort()

    def canceled(self) -> None:
        self._inner.canceled()

    def destroy(self) -> None:
        pass


class ActionServer:
    """rclpy's ActionServer. Each accepted goal gets a thread of its own (hetros's action server), which calls
    ``handle_accepted_callback`` and then, once the goal is to execute, ``execute_callback``; a coroutine
    callback is driven to its end in that thread."""

    def __init__(self, node: Any, action_type: Any, action_name: str, execute_callback: Callable[..., Any], *,
                 callback_group: Any = None,
                 goal_callback: Callable[[Any], GoalResponse] = default_goal_callback,
                 handle_accepted_callback: Callable[[ServerGoalHandle], None] = default_handle_accepted_callback,
                 cancel_callback: Callable[[Any], CancelResponse] = default_cancel_callback,
                 result_timeout: int = 900, **_qos: Any) -> None:
        self._node = node
        self._type = action_type
        self._execute_callback = execute_callback
        self._goal_callback = goal_callback
        self._handle_accepted_callback = handle_accepted_callback
        self._cancel_callback = cancel_callback
        self._handles: dict[bytes, ServerGoalHandle] = {}
        self._lock = threading.Lock()
        self._stop = node._hetros.graph.stop
        self._inner = HetrosActionServer(
            node._hetros, action_type, node.resolve_topic_name(action_name), self._run,
            goal_callback=lambda goal: self._goal_callback(received(goal)) == GoalResponse.ACCEPT,
            cancel_callback=lambda goal: self._cancel_callback(self._handle(goal)) == CancelResponse.ACCEPT,
            result_timeout=float(result_timeout))
        # where looks from outside find it (`hetros action send_goal`), as a server made by the hetros API
        node._hetros.action_servers.setdefault(self._inner.name, self._inner)

    def _handle(self, inner: HetrosGoalHandle) -> ServerGoalHandle:
        with self._lock:
            handle = self._handles.get(inner.goal_id)
            if handle is None:
                handle = self._handles[inner.goal_id] = ServerGoalHandle(inner, self._type)
            return handle

    def register_handle_accepted_callback(self, callback: Callable[[ServerGoalHandle], None]) -> None:
        self._handle_accepted_callback = callback

    def register_goal_callback(self, callback: Callable[[Any], GoalResponse]) -> None:
        self._goal_callback = callback

    def register_cancel_callback(self, callback: Callable[[Any], CancelResponse]) -> None:
        self._cancel_callback = callback

    def register_execute_callback(self, callback: Callable[..., Any]) -> None:
        self._execute_callback = callback

    def _run(self, inner: HetrosGoalHandle) -> Any:
        handle = self._handle(inner)
        try:
            self._handle_accepted_callback(handle)
            while not handle._executing.wait(0.1):
                if not inner.is_active or self._stop.is_set():
                    return None  # ended before it executed (aborted for a newer goal, say)
            result = self._execute_callback(handle)
            if inspect.iscoroutine(result):
                result = run_to_end(result, self._stop)
            if inner.is_active:
                log.warning("Goal state not set, assuming aborted. Goal ID: %s", handle.goal_id.uuid)
                inner.abort()
            where = f"the result of action {self._inner.name}"
            return None if result is None else copied(result, self._type.Result, where)
        finally:
            with self._lock:
                self._handles.pop(inner.goal_id, None)

    def destroy(self) -> None:
        self._inner.close()
