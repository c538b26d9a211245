"""rclpy.action.client on hetros's action client: futures completed in the node's executor, feedback
callbacks given rclpy's feedback message (``feedback.feedback.sequence``)."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import Any

from ....runtime import ActionClient as HetrosActionClient
from ....runtime import ClientGoalHandle as HetrosGoalHandle
from ....runtime import uuid_message
from ..._flavour import copied, flavoured_action, received
from ..executors import spin_until_done
from ..task import Future


class ClientGoalHandle:
    """A goal this client sent: ``accepted``, ``status``, and its result and cancel as futures."""

    def __init__(self, client: ActionClient, inner: HetrosGoalHandle) -> None:
        self._client = client
        self._inner = inner

    @property
    def goal_id(self) -> Any:
        return uuid_message(self._inner.goal_id)

    @property
    def stamp(self) -> Any:
        return self._inner.stamp

    @property
    def accepted(self) -> bool:
        return self._inner.accepted

    @property
    def status(self) -> int:
        return int(self._inner.status)

    def get_result_async(self) -> Future:
        """Completes with the ``GetResult`` response (``.status``, ``.result``) once every feedback of the goal
        reached its callback."""
        inner = self._client._inner

        def response(done: Any) -> Any:
            inner._serve()  # feedback sent before the goal ended goes first
            self._inner.status = type(self._inner.status)(int(done.status))
            return received(done)
        return Future.wrapping(self._inner.result_async(), response, self._client._schedule)

    def get_result(self) -> Any:
        future = self.get_result_async()
        spin_until_done(self._client._node._hetros, future, None)
        return future.result()

    def cancel_goal_async(self) -> Future:
        return Future.wrapping(self._client._inner.cancel_async(self._inner.goal_id), received,
                               self._client._schedule)

    def cancel_goal(self) -> Any:
        future = self.cancel_goal_async()
        spin_until_done(self._client._node._hetros, future, None)
        return future.result()


class ActionClient:
    def __init__(self, node: Any, action_type: Any, action_name: str, *, callback_group: Any = None,
                 **_qos: Any) -> None:
        self._node = node
        self._type = flavoured_action(action_type)
        self._inner = HetrosActionClient(node._hetros, action_type, node.resolve_topic_name(action_name))

    def _schedule(self, work: Callable[[], None]) -> None:
        self._node._hetros.executor.add_timer(time.monotonic(), work)

    def wait_for_server(self, timeout_sec: float | None = None) -> bool:
        """True: the plan wires the client to its server before the graph starts, and goals wait in the
        server's queue until it takes them."""
        return True

    def server_is_ready(self) -> bool:
        return True

    def send_goal_async(self, goal: Any, feedback_callback: Callable[[Any], None] | None = None,
                        goal_uuid: Any = None) -> Future:
        """Completes with the goal's ClientGoalHandle once the server accepted or rejected it."""
        goal_id = os.urandom(16) if goal_uuid is None else bytes(goal_uuid.uuid)
        relay = None
        if feedback_callback is not None:
            callback = feedback_callback
            message_type = self._type.FeedbackMessage

            def relay(feedback: Any) -> None:
                message = message_type(goal_id=uuid_message(goal_id), feedback=received(feedback))
                self._schedule(lambda: callback(message))
        sent = self._inner.send_goal_async(copied(goal, self._type.Goal, f"a goal of action {self._inner.name}"), relay,
                                           goal_id)
        return Future.wrapping(sent, lambda inner: ClientGoalHandle(self, inner), self._schedule)

    def send_goal(self, goal: Any, feedback_callback: Callable[[Any], None] | None = None,
                  goal_uuid: Any = None) -> Any:
        """Send ``goal`` and wait for its end: the ``GetResult`` response (``.status``, ``.result``)."""
        future = self.send_goal_async(goal, feedback_callback, goal_uuid)
        spin_until_done(self._node._hetros, future, None)
        handle: ClientGoalHandle = future.result()
        return handle.get_result() if handle.accepted else None

    def destroy(self) -> None:
        self._inner.close()
