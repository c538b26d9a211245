"""Actions across the ROS 1 bridge: hetros action servers for actionlib clients, and back.

Exported: the bridge is a hetros action client and, towards ROS 1, an actionlib server
(subscribes ``goal`` and ``cancel``; publishes ``status`` at 5 Hz and on every change,
``feedback`` and ``result``). Imported: the bridge is a hetros action server whose
``execute`` is an actionlib client of the ROS 1 server. Goal states map one to one where
they can (accepted = PENDING, executing = ACTIVE, canceling = PREEMPTING, canceled =
PREEMPTED, a rejected goal = REJECTED); goal ids map through a table, ROS 1's strings on one
side and hetros' UUIDs on the other.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any

from ..._errors import Error
from ..._log import get_logger
from ...msg import ActionType
from ...runtime import ClientGoalHandle, GoalStatus, Node, ServerGoalHandle
from ...transport.tcpros import (
    ABORTED,
    ACTIVE,
    PENDING,
    PREEMPTED,
    PREEMPTING,
    RECALLED,
    REJECTED,
    SUCCEEDED,
    TERMINAL,
    Ros1ActionType,
    Ros1Peer,
)

log = get_logger("hetros.ros1.actions")
# how long actionlib servers keep a finished goal in their status list
STATUS_KEPT = 5.0
# how long an imported action waits for its ROS 1 server to be connected before aborting a goal
SERVER_WAIT = 10.0
_TO_ROS1 = {GoalStatus.UNKNOWN: PENDING, GoalStatus.ACCEPTED: PENDING, GoalStatus.EXECUTING: ACTIVE,
            GoalStatus.CANCELING: PREEMPTING, GoalStatus.SUCCEEDED: SUCCEEDED, GoalStatus.CANCELED: PREEMPTED,
            GoalStatus.ABORTED: ABORTED}


def _stamp_ns(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


@dataclass
class _Goal:
    goal_id: Any  # actionlib_msgs/GoalID (ROS 1)
    status: int = PENDING
    handle: ClientGoalHandle | None = None
    cancel_requested: bool = False
    finished_at: float = 0.0


class ExportedAction:
    """A hetros action server offered to ROS 1 actionlib clients."""

    def __init__(self, node: Node, peer: Ros1Peer, action_type: ActionType, name: str,
                 kind: Ros1ActionType) -> None:
        self._node = node
        self._kind = kind
        self.name = name.rstrip("/")
        self._client = node.create_action_client(action_type, name)
        self._lock = threading.Lock()
        self._goals: dict[str, _Goal] = {}
        self._ids = 0
        self._status = peer.advertise(f"{self.name}/status", kind.status)
        self._feedback = peer.advertise(f"{self.name}/feedback", kind.feedback)
        self._result = peer.advertise(f"{self.name}/result", kind.result)
        peer.subscribe(f"{self.name}/goal", kind.goal, self._on_goal)
        peer.subscribe(f"{self.name}/cancel", kind.cancel, self._on_cancel)
        self._peer_name = peer.name
        node.create_timer(0.2, self.publish_status)

    def _on_goal(self, message: Any) -> None:
        goal_id = message.goal_id
        if not goal_id.id:  # actionlib servers name goals their clients left unnamed
            with self._lock:
                self._ids += 1
                goal_id = self._kind.goal_id(f"{self._peer_name}-{self._ids}-{time.time():.6f}", goal_id.stamp)
        if _stamp_ns(goal_id.stamp) == 0:
            goal_id = self._kind.goal_id(goal_id.id)
        with self._lock:
            if goal_id.id in self._goals:
                return
            tracked = self._goals[goal_id.id] = _Goal(goal_id)
        threading.Thread(target=self._run, args=(tracked, message.goal), daemon=True,
                         name=f"ros1-goal:{self.name}").start()
        self.publish_status()

    def _run(self, tracked: _Goal, ros1_goal: Any) -> None:
        kind = self._kind

        def feedback(message: Any) -> None:
            self._feedback.publish(kind.feedback.cls(
                header=kind.header(), status=kind.goal_status(tracked.goal_id, ACTIVE),
                feedback=kind.inner["Feedback"].to_ros1(message)))

        result: Any = None
        try:
            handle = self._client.send_goal(kind.inner["Goal"].from_ros1(ros1_goal), feedback_cb=feedback)
            if not handle.accepted:
                self._finish(tracked, REJECTED, None)
                return
            with self._lock:
                tracked.handle = handle
                cancel = tracked.cancel_requested
            if cancel:
                handle.cancel()
            result = handle.result()
            self._finish(tracked, _TO_ROS1[handle.status], result)
        except Error as exc:
            if not self._node.graph.stop.is_set():
                log.error("action %s: goal %s from ROS 1 failed: %s", self.name, tracked.goal_id.id, exc)
                self._finish(tracked, ABORTED, None)

    def _finish(self, tracked: _Goal, status: int, result: Any) -> None:
        kind = self._kind
        inner = kind.inner["Result"]
        with self._lock:
            tracked.status = status
            tracked.finished_at = time.monotonic()
        self._result.publish(kind.result.cls(
            header=kind.header(), status=kind.goal_status(tracked.goal_id, status),
            result=inner.to_ros1(result if result is not None else inner.empty())))
        self.publish_status()

    def _on_cancel(self, message: Any) -> None:
        everything = not message.id and _stamp_ns(message.stamp) == 0
        before = _stamp_ns(message.stamp)
        with self._lock:
            chosen = [g for g in self._goals.values() if g.status not in TERMINAL and (
                everything or (message.id and g.goal_id.id == message.id)
                or (before and _stamp_ns(g.goal_id.stamp) <= before))]
            for tracked in chosen:
                tracked.cancel_requested = True
            handles = [g.handle for g in chosen if g.handle is not None]
        for handle in handles:
            threading.Thread(target=handle.cancel, daemon=True, name=f"ros1-cancel:{self.name}").start()

    def publish_status(self) -> None:
        kind = self._kind
        now = time.monotonic()
        with self._lock:
            for key in [k for k, g in self._goals.items() if g.finished_at and now - g.finished_at > STATUS_KEPT]:
                del self._goals[key]
            statuses = []
            for tracked in self._goals.values():
                status = tracked.status
                if tracked.handle is not None and status not in TERMINAL:
                    status = _TO_ROS1[tracked.handle.status]
                statuses.append(kind.goal_status(tracked.goal_id, status))
        self._status.publish(kind.status.cls(header=kind.header(), status_list=statuses))


@dataclass
class _Pending:
    handle: ServerGoalHandle
    done: threading.Event = field(default_factory=threading.Event)
    result: Any = None


class ImportedAction:
    """A ROS 1 actionlib server offered to hetros action clients."""

    def __init__(self, node: Node, peer: Ros1Peer, action_type: ActionType, name: str,
                 kind: Ros1ActionType) -> None:
        self._node = node
        self._kind = kind
        self._peer_name = peer.name
        self.name = name.rstrip("/")
        self._lock = threading.Lock()
        self._pending: dict[str, _Pending] = {}
        self._server_seen = threading.Event()
        self._goal = peer.advertise(f"{self.name}/goal", kind.goal)
        self._cancel = peer.advertise(f"{self.name}/cancel", kind.cancel)
        peer.subscribe(f"{self.name}/status", kind.status, lambda _status: self._server_seen.set())
        self._feedback = peer.subscribe(f"{self.name}/feedback", kind.feedback, self._on_feedback)
        self._result = peer.subscribe(f"{self.name}/result", kind.result, self._on_result)
        node.create_action_server(action_type, name, self._execute, max_goals=64)

    def _connected(self) -> bool:
        """The server hears goals and cancels, and its feedback and result reach us: a goal sent
        before the feedback connection is up would lose its first feedback messages (not latched)."""
        return bool(self._server_seen.is_set() and self._goal.subscribers and self._cancel.subscribers
                    and self._feedback.publishers and self._result.publishers)

    def _execute(self, handle: ServerGoalHandle) -> Any:
        kind = self._kind
        stop = self._node.graph.stop
        deadline = time.monotonic() + SERVER_WAIT
        while not self._connected():
            if stop.is_set():
                return None
            if time.monotonic() > deadline:
                log.error("action %s: no ROS 1 actionlib server answered within %g s; goal aborted",
                          self.name, SERVER_WAIT)
                handle.abort()
                return None
            time.sleep(0.02)
        goal_id = kind.goal_id(f"{self._peer_name}-{handle.goal_id.hex()}")
        pending = _Pending(handle)
        with self._lock:
            self._pending[goal_id.id] = pending
        try:
            self._goal.publish(kind.goal.cls(header=kind.header(), goal_id=goal_id,
                                             goal=kind.inner["Goal"].to_ros1(handle.request)))
            canceled = False
            while not pending.done.wait(0.02):
                if stop.is_set():
                    return None
                if handle.is_cancel_requested and not canceled:
                    self._cancel.publish(kind.goal_id(goal_id.id, kind.stamp(0.0)))
                    canceled = True
        finally:
            with self._lock:
                self._pending.pop(goal_id.id, None)
        message = pending.result
        result = kind.inner["Result"].from_ros1(message.result)
        status = int(message.status.status)
        if status == SUCCEEDED:
            return result
        if status in (PREEMPTED, RECALLED) and handle.is_cancel_requested:
            handle.canceled(result)
        else:
            if message.status.text:
                log.warning("action %s: the ROS 1 server ended a goal with status %d: %s", self.name, status,
                            message.status.text)
            handle.abort(result)
        return None

    def _on_feedback(self, message: Any) -> None:
        with self._lock:
            pending = self._pending.get(message.status.goal_id.id)
        if pending is not None and pending.handle.is_active:
            pending.handle.publish_feedback(self._kind.inner["Feedback"].from_ros1(message.feedback))

    def _on_result(self, message: Any) -> None:
        with self._lock:
            pending = self._pending.get(message.status.goal_id.id)
        if pending is not None:
            pending.result = message
            pending.done.set()
