"""Actions: ROS 2's goal, feedback, result and cancel, on whatever carries services and topics.

An action is three services and two topics (``hetros.plan.action_endpoints``), as in ROS 2,
so every transport carries it unchanged. What the node API adds is the goal state machine
(accepted → executing → canceling → succeeded | aborted | canceled), a thread per executing
goal, and replies that wait: ``get_result`` is answered when the goal ends, not when asked.

Each server and client has one helper thread that serves its requests and replies. It waits
on the node's executor like any other waiter, so it also receives shared-memory wake-ups
when the node's own thread is busy in a long callback or in a loop that never spins.
"""

from __future__ import annotations

import enum
import os
import threading
import time
import traceback
from collections import OrderedDict, deque
from collections.abc import Callable
from concurrent.futures import Future
from typing import TYPE_CHECKING, Any

import numpy as np

from .._errors import (
    ActionError,
    ActionTimeoutError,
    GoalRejectedError,
    NodeError,
    ShutdownError,
    TopicTypeError,
    UndeclaredEndpointError,
)
from .._log import get_logger
from ..msg import ActionKind, ActionType, registry
from ..msg import action_type as as_action_type
from ..plan import action_endpoints, request_channel
from ..transport import Reader
from ._entities import Client, Replies, check_type, typename_of

if TYPE_CHECKING:
    from ._node import Node

class GoalStatus(enum.IntEnum):
    """A goal's state, numbered as ``action_msgs/msg/GoalStatus``."""

    UNKNOWN = 0
    ACCEPTED = 1
    EXECUTING = 2
    CANCELING = 3
    SUCCEEDED = 4
    CANCELED = 5
    ABORTED = 6


UNKNOWN, ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = GoalStatus
STATUS_NAMES = tuple(s.name.lower() for s in GoalStatus)
_TERMINAL = frozenset((SUCCEEDED, CANCELED, ABORTED))
# action_msgs/srv/CancelGoal return codes
_CANCEL_NONE, _CANCEL_REJECTED, _CANCEL_UNKNOWN, _CANCEL_TERMINATED = range(4)
# ROS 2 keeps a finished goal's result for 15 minutes; hetros also bounds how many it keeps
RESULT_TIMEOUT = 900.0
MAX_KEPT_RESULTS = 1000
# how often a helper thread looks at the clock (result expiry) when nothing wakes it
_TICK = 0.5
# how long closing a server waits for executing goals to notice the cancel and end
_CLOSE_GRACE = 2.0

log = get_logger("hetros.action")


def _short(goal_id: bytes) -> str:
    return goal_id.hex()[:8]


def _now_stamp() -> Any:
    now = time.time_ns()
    return registry().get("builtin_interfaces/msg/Time")(sec=now // 1_000_000_000, nanosec=now % 1_000_000_000)


def uuid_message(goal_id: bytes) -> Any:
    """``unique_identifier_msgs/msg/UUID`` of a 16-byte goal id."""
    return registry().get("unique_identifier_msgs/msg/UUID")(uuid=np.frombuffer(goal_id, np.uint8).copy())


def _stamp_ns(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


class _Helper:
    """The one thread of an action endpoint: run ``work`` whenever the node's executor may have news."""

    def __init__(self, node: Node, name: str, work: Callable[[], None]) -> None:
        self._node = node
        self._work = work
        self.closed = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _run(self) -> None:
        executor = self._node.executor
        while not self.closed:
            seen = executor.generation
            try:
                self._work()
            except Exception:  # a bug here must not silently end every later goal
                log.exception("%s failed; it keeps serving", self._thread.name)
            if self._node.graph.stop.is_set():
                return
            executor.wait(seen, _TICK)

    def close(self) -> None:
        self.closed = True
        self._node.executor.wake()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(_CLOSE_GRACE)


Endpoints = dict[str, tuple[str, str]]


def _checked_endpoints(node: Node, action_type: ActionType, name: str, role: str) -> tuple[Endpoints, Endpoints]:
    """The action's services and topics (part -> (name, type)), once the project file is seen to agree."""
    plan = node.graph.plan
    if plan is not None and node.name in plan.nodes:
        section = "actions" if role == "server" else "action_clients"
        declared = getattr(plan.nodes[node.name], section).get(name)
        if declared is None:
            raise UndeclaredEndpointError(
                f"node {node.name!r} creates an action {role} of {name!r} that the project file does not "
                f"declare: add `{name}: {action_type.name}` under nodes.{node.name}.{section}"
            )
        if declared != action_type.name:
            raise TopicTypeError(f"node {node.name!r} uses action {name} with type {action_type.name}, but the "
                                 f"project declares {declared}; make the code and nodes.{node.name}.{section} agree")
    services, topics = action_endpoints(name, action_type.name)
    return ({n.rsplit("/", 1)[1]: (n, t) for n, t in services.items()},
            {n.rsplit("/", 1)[1]: (n, t) for n, t in topics.items()})


# -- server ------------------------------------------------------------------------------------


class ServerGoalHandle:
    """One goal on the server: its request, its state, and the calls that move it on."""

    def __init__(self, server: ActionServer, goal_id: bytes, request: Any) -> None:
        self.server = server
        self.goal_id = goal_id
        self.request = request
        self.stamp = _now_stamp()
        self.status = ACCEPTED
        self.result: Any = None
        self.finished_at = 0.0
        self._waiting: list[tuple[int, str]] = []  # get_result requests answered when the goal ends
        # inside an execute callback, succeed/abort/canceled decide how the goal ends and the
        # callback's return value is its result (rclpy's contract): the goal ends on return
        self._in_execute = False
        self._decided: tuple[int, Any] | None = None
        # who else hears this goal's feedback as it is published (`hetros action send_goal -f`)
        self.feedback_listeners: list[Callable[[Any], None]] = []

    def __repr__(self) -> str:
        return f"<goal {_short(self.goal_id)} of {self.server.name}: {STATUS_NAMES[self.status]}>"

    @property
    def is_cancel_requested(self) -> bool:
        return self.status == CANCELING

    @property
    def is_active(self) -> bool:
        """Not ended, nor decided to end by ``succeed``/``abort``/``canceled`` (as in rclpy)."""
        return self.status not in _TERMINAL and self._decided is None

    @property
    def _open(self) -> bool:
        """Not ended yet (a goal decided inside its execute callback ends when that returns)."""
        return self.status not in _TERMINAL

    @property
    def _ended(self) -> int | None:
        """How the goal ended or was decided to end; None while it is open."""
        if self._decided is not None:
            return self._decided[0]
        return None if self.status not in _TERMINAL else int(self.status)

    def publish_feedback(self, feedback: Any) -> None:
        self.server.publish_feedback(self, feedback)

    def succeed(self, result: Any = None) -> None:
        self.server.succeed(self, result)

    def abort(self, result: Any = None) -> None:
        self.server.abort(self, result)

    def canceled(self, result: Any = None) -> None:
        self.server.canceled(self, result)


class ActionServer:
    """Serves one action.

    Callback style: ``execute(goal_handle)`` runs in a thread of its own per goal (at most
    ``max_goals`` at once; later goals wait, accepted) and returns the result, as in rclpy:
    ``succeed()``/``abort()``/``canceled()`` called inside it say how the goal ends, and the
    goal ends with the returned value when the callback returns (``succeed(result)``'s
    argument stands where it returns None). A goal it leaves without one of them succeeds,
    or is canceled when a cancel was requested; one that raises, or returns something that
    is not the action's result, is aborted and logged. Thread style (no ``execute``): the
    node takes goals with :meth:`take_goal` and ends them with :meth:`succeed` and friends.
    """

    def __init__(self, node: Node, action_type: ActionKind, name: str,
                 execute: Callable[[ServerGoalHandle], Any] | None = None, *,
                 goal_callback: Callable[[Any], bool] | None = None,
                 cancel_callback: Callable[[ServerGoalHandle], bool] | None = None,
                 max_goals: int | None = None, result_timeout: float = RESULT_TIMEOUT) -> None:
        action_type = as_action_type(action_type)
        services, topics = _checked_endpoints(node, action_type, name, "server")
        plan = node.graph.plan
        planned = plan.nodes[node.name].max_goals.get(name) if plan is not None and node.name in plan.nodes else None
        self.max_goals = max_goals or planned or 8
        if self.max_goals < 1:
            raise NodeError(f"max_goals must be at least 1, not {self.max_goals!r}")
        self.node = node
        self.type = action_type
        self.name = name
        self.execute = execute
        self.goal_callback = goal_callback
        self.cancel_callback = cancel_callback
        self.result_timeout = result_timeout
        self._services = services
        self._lock = threading.RLock()
        self._changed = threading.Condition(self._lock)
        self._goals: OrderedDict[bytes, ServerGoalHandle] = OrderedDict()
        self._waiting_goals: deque[ServerGoalHandle] = deque()  # accepted, not yet executing
        self._threads: dict[bytes, threading.Thread] = {}
        self._closed = False
        graph = node.graph
        self._requests: dict[str, Reader] = {}
        self._types = {part: graph.types.get_service(srv) for part, (_, srv) in services.items()}
        self._replies = {part: Replies(node, service, typename_of(self._types[part].Response))
                         for part, (service, _srv) in services.items()}
        for part, (service, srv) in services.items():
            node._check_declared_type(request_channel(service), f"{srv}_Request")
            self._requests[part] = graph.open_reader(request_channel(service), node.name, f"{srv}_Request",
                                                     node.executor.wake, envelope=True)
        self._feedback = graph.open_writer(topics["feedback"][0], node.name, topics["feedback"][1])
        self._status = graph.open_writer(topics["status"][0], node.name, topics["status"][1])
        self._feedback_type = action_type.FeedbackMessage
        self._helper = _Helper(node, f"action-server:{name}", self._serve)
        self._helper.start()

    # -- requests ----------------------------------------------------------------------------

    def _serve(self) -> None:
        handlers = {"send_goal": self._on_send_goal, "cancel_goal": self._on_cancel,
                    "get_result": self._on_get_result}
        while True:
            idle = True
            for part, reader in self._requests.items():
                envelope = reader.try_take()
                if envelope is not None:
                    idle = False
                    request_id, client, request = envelope
                    handlers[part](request_id, client, request)
            if idle:
                break
        self._expire()

    def _reply(self, part: str, request_id: int, client: str, response: Any) -> None:
        self._replies[part].send(request_id, client, response)

    def _on_send_goal(self, request_id: int, client: str, request: Any) -> None:
        self._admit(bytes(request.goal_id.uuid), request.goal, client,
                    lambda response: self._reply("send_goal", request_id, client, response))

    def submit(self, goal: Any) -> ServerGoalHandle | None:
        """A goal from the command line (``hetros action send_goal``), admitted as a client's would be:
        its handle, or None when rejected. Run in the server node's executor."""
        return self._admit(os.urandom(16), goal, "hetros action send_goal", lambda response: None)

    def _admit(self, goal_id: bytes, goal: Any, client: str,
               reply: Callable[[Any], None]) -> ServerGoalHandle | None:
        accepted = False
        with self._lock:
            duplicate = goal_id in self._goals
        if duplicate:
            log.warning("action %s: goal %s from %s reuses a goal id; rejected", self.name, _short(goal_id), client)
        elif self._closed or self.node.graph.stop.is_set():
            pass
        else:
            try:
                accepted = True if self.goal_callback is None else bool(self.goal_callback(goal))
            except Exception:
                log.exception("action %s: goal_callback raised; goal %s rejected", self.name, _short(goal_id))
        handle = ServerGoalHandle(self, goal_id, goal)
        response = self._types["send_goal"].Response(accepted=accepted, stamp=handle.stamp)
        if not accepted:
            reply(response)
            return None
        with self._lock:
            self._goals[goal_id] = handle
        reply(response)
        with self._lock:
            self._waiting_goals.append(handle)
            self._publish_status()
            self._changed.notify_all()
        if self.execute is not None:
            self._start_goals()
        return handle

    def _on_get_result(self, request_id: int, client: str, request: Any) -> None:
        goal_id = bytes(request.goal_id.uuid)
        with self._lock:
            handle = self._goals.get(goal_id)
            if handle is not None and handle._open:
                handle._waiting.append((request_id, client))
                return
        if handle is None:
            response = self._types["get_result"].Response(status=UNKNOWN, result=self.type.Result())
        else:
            response = self._result_response(handle)
        self._reply("get_result", request_id, client, response)

    def _result_response(self, handle: ServerGoalHandle) -> Any:
        result = handle.result if handle.result is not None else self.type.Result()
        return self._types["get_result"].Response(status=handle.status, result=result)

    def _on_cancel(self, request_id: int, client: str, request: Any) -> None:
        info = request.goal_info
        goal_id = bytes(info.goal_id.uuid)
        before = _stamp_ns(info.stamp)
        everything = not any(goal_id) and before == 0
        canceling = []
        code = _CANCEL_NONE
        with self._lock:
            chosen = [h for h in self._goals.values()
                      if everything or (any(goal_id) and h.goal_id == goal_id)
                      or (before and _stamp_ns(h.stamp) <= before)]
            for handle in chosen:
                if not handle._open:
                    continue
                if handle.status == CANCELING:
                    canceling.append(handle)
                    continue
                try:
                    agreed = True if self.cancel_callback is None else bool(self.cancel_callback(handle))
                except Exception:
                    log.exception("action %s: cancel_callback raised; cancel of %s refused", self.name, handle)
                    agreed = False
                if agreed:
                    canceling.append(handle)
                    if handle in self._waiting_goals:  # nobody executes it yet: canceled at once
                        self._waiting_goals.remove(handle)
                        self._finish(handle, CANCELED, None)
                    else:
                        handle.status = CANCELING
            if not canceling:
                known = self._goals.get(goal_id) if any(goal_id) else None
                if any(goal_id) and known is None and not before:
                    code = _CANCEL_UNKNOWN
                elif known is not None and not known._open and not before:
                    code = _CANCEL_TERMINATED
                else:
                    code = _CANCEL_REJECTED
            self._publish_status()
            self._changed.notify_all()
        goal_info = registry().get("action_msgs/msg/GoalInfo")
        response = self._types["cancel_goal"].Response(
            return_code=code,
            goals_canceling=[goal_info(goal_id=uuid_message(h.goal_id), stamp=h.stamp) for h in canceling])
        self._reply("cancel_goal", request_id, client, response)

    # -- goals -------------------------------------------------------------------------------

    def _start_goals(self) -> None:
        with self._lock:
            while self._waiting_goals and len(self._threads) < self.max_goals and not self._closed:
                handle = self._waiting_goals.popleft()
                handle.status = EXECUTING
                thread = threading.Thread(target=self._execute, args=(handle,), daemon=True,
                                          name=f"goal:{self.name}:{_short(handle.goal_id)}")
                self._threads[handle.goal_id] = thread
                thread.start()
            self._publish_status()

    def _execute(self, handle: ServerGoalHandle) -> None:
        assert self.execute is not None
        handle._in_execute = True
        status: int = ABORTED
        result: Any = None
        try:
            returned = self.execute(handle)
            if returned is not None:
                self._check_result(returned)
        except ShutdownError:
            pass
        except Exception:
            log.error("action %s: execute raised; goal %s aborted:\n%s", self.name, _short(handle.goal_id),
                      traceback.format_exc())
        else:
            decided = handle._decided
            if decided is not None:
                status, result = decided[0], returned if returned is not None else decided[1]
            else:
                status, result = (CANCELED if handle.is_cancel_requested else SUCCEEDED), returned
        finally:
            with self._lock:
                self._threads.pop(handle.goal_id, None)
                handle._in_execute = False
                if handle._open:  # else ended outside the callback meanwhile
                    self._finish(handle, status, result)
                    self._publish_status()
            self._start_goals()

    def take_goal(self, timeout: float | None = None) -> ServerGoalHandle:
        """The next accepted goal, now executing (thread style); blocks until one comes.

        Raises ActionTimeoutError after ``timeout`` seconds, ShutdownError on shutdown.
        """
        if self.execute is not None:
            raise NodeError(f"action server {self.name} runs an execute callback; take_goal is for servers "
                            "created without one")
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._lock:
            while not self._waiting_goals:
                if self.node.graph.stop.is_set() or self._closed:
                    raise ShutdownError(f"take_goal on {self.name} interrupted: the graph is shutting down")
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    raise ActionTimeoutError(f"no goal for action {self.name} within {timeout:g} s")
                self._changed.wait(_TICK if left is None else min(left, _TICK))
            handle = self._waiting_goals.popleft()
            handle.status = EXECUTING
            self._publish_status()
            return handle

    def publish_feedback(self, handle: ServerGoalHandle, feedback: Any) -> None:
        """Send ``feedback`` to the clients of ``handle``'s goal (in order, reliably)."""
        check_type(feedback, typename_of(self.type.Feedback), f"feedback of action {self.name}")
        if not handle.is_active:
            raise ActionError(f"goal {_short(handle.goal_id)} of {self.name} already ended "
                              f"({STATUS_NAMES[handle.status]}); it takes no more feedback")
        message = self._feedback_type(goal_id=uuid_message(handle.goal_id), feedback=feedback)
        with self._lock:
            self._feedback.write(message)
        for listener in list(handle.feedback_listeners):
            listener(feedback)

    def succeed(self, handle: ServerGoalHandle, result: Any = None) -> None:
        self._end(handle, SUCCEEDED, result)

    def abort(self, handle: ServerGoalHandle, result: Any = None) -> None:
        self._end(handle, ABORTED, result)

    def canceled(self, handle: ServerGoalHandle, result: Any = None) -> None:
        """End a goal whose cancel was requested (``is_cancel_requested``) as canceled."""
        if handle.status != CANCELING:
            raise ActionError(f"goal {_short(handle.goal_id)} of {self.name} is {STATUS_NAMES[handle.status]}, "
                              "not canceling: only a goal a client asked to cancel can end canceled; "
                              "call succeed() or abort()")
        self._end(handle, CANCELED, result)

    def _check_result(self, result: Any) -> None:
        check_type(result, typename_of(self.type.Result), f"the result of action {self.name}")
        result._hetros_validate(result, f"the result of {self.name}")

    def _end(self, handle: ServerGoalHandle, status: int, result: Any) -> None:
        if result is not None:
            self._check_result(result)
        with self._lock:
            ended = handle._ended
            if ended is not None:
                raise ActionError(f"goal {_short(handle.goal_id)} of {self.name} already ended "
                                  f"({STATUS_NAMES[ended]}); a goal ends once")
            if handle._in_execute:
                handle._decided = (status, result)  # ends with the callback's return value
                return
            self._finish(handle, status, result)
            self._publish_status()

    def _finish(self, handle: ServerGoalHandle, status: int, result: Any) -> None:
        """Make ``handle`` terminal and answer every get_result waiting for it (lock held)."""
        handle.status = GoalStatus(status)
        handle.result = result
        handle.finished_at = time.monotonic()
        waiting, handle._waiting = handle._waiting, []
        response = self._result_response(handle)
        for request_id, client in waiting:
            try:
                self._reply("get_result", request_id, client, response)
            except Exception:
                log.exception("action %s: could not send the result of %s to %s", self.name, handle, client)

    def _expire(self) -> None:
        now = time.monotonic()
        with self._lock:
            finished = [h for h in self._goals.values() if not h._open]
            excess = len(finished) - MAX_KEPT_RESULTS
            expired = [h for i, h in enumerate(finished)
                       if i < excess or now - h.finished_at > self.result_timeout]
            for handle in expired:
                del self._goals[handle.goal_id]
            if expired:
                self._publish_status()

    def _publish_status(self) -> None:
        types = registry()
        status, info = types.get("action_msgs/msg/GoalStatus"), types.get("action_msgs/msg/GoalInfo")
        message = types.get("action_msgs/msg/GoalStatusArray")(status_list=[
            status(goal_info=info(goal_id=uuid_message(h.goal_id), stamp=h.stamp), status=h.status)
            for h in self._goals.values()
        ])
        self._status.write(message)

    @property
    def goals(self) -> list[ServerGoalHandle]:
        with self._lock:
            return list(self._goals.values())

    def close(self) -> None:
        """Ask executing goals to cancel, give them a moment, abort what is left, then stop serving.

        When the node failed and the graph stops for it, unfinished goals are left unanswered:
        their clients then fail with the graph's stop reason ("node sorter failed"), which says
        more than an aborted status would.
        """
        with self._lock:
            if self._closed:
                return
            self._closed = True
            for handle in self._goals.values():
                if handle.status in (ACCEPTED, EXECUTING):
                    handle.status = CANCELING
            threads = list(self._threads.values())
            self._changed.notify_all()
        deadline = time.monotonic() + _CLOSE_GRACE
        for thread in threads:
            thread.join(max(deadline - time.monotonic(), 0.0))
        with self._lock:
            for handle in self._goals.values():
                if handle._open:
                    if self.node.failing:
                        handle._waiting.clear()
                    self._finish(handle, ABORTED, None)
            try:
                self._publish_status()
            except Exception:
                log.debug("action %s: final status not sent", self.name, exc_info=True)
        self._helper.close()
        try:
            if not self.node.failing:
                self._serve()  # requests that came in meanwhile: results are answered, new goals rejected
        except Exception:
            log.debug("action %s: last requests not answered", self.name, exc_info=True)
        for reader in self._requests.values():
            reader.close()
        self.node.executor.entities -= 1


# -- client ------------------------------------------------------------------------------------


class ClientGoalHandle:
    """A goal sent by a client: wait for its ``result``, ``cancel`` it, watch its ``status``."""

    def __init__(self, client: ActionClient, goal_id: bytes, feedback_cb: Callable[[Any], object] | None) -> None:
        self.client = client
        self.goal_id = goal_id
        self.feedback_cb = feedback_cb
        self.accepted = False
        self.stamp: Any = None
        self.status = UNKNOWN
        self._result: Future[Any] | None = None

    def __repr__(self) -> str:
        return f"<goal {_short(self.goal_id)} on {self.client.name}: {STATUS_NAMES[self.status]}>"

    def result(self, timeout: float | None = None) -> Any:
        """Wait for the goal to end and return its result message; ``status`` then says how it ended.

        Raises GoalRejectedError for a rejected goal, ActionTimeoutError after ``timeout``,
        and ActionError naming the cause when the graph stops first (its server died, say).
        """
        if not self.accepted or self._result is None:
            raise GoalRejectedError(f"goal {_short(self.goal_id)} on {self.client.name} was rejected by the server; "
                                    "it has no result")
        response = self.client._wait(self._result, timeout, f"the result of goal {_short(self.goal_id)}")
        self.client._serve()
        self.client._forget(self.goal_id)
        self.status = GoalStatus(int(response.status))
        return response.result

    def result_async(self) -> Future[Any]:
        """The future of the server's ``GetResult`` response (``status`` and ``result``) for this accepted goal."""
        if not self.accepted or self._result is None:
            raise GoalRejectedError(f"goal {_short(self.goal_id)} on {self.client.name} was rejected by the server; "
                                    "it has no result")
        return self._result

    def cancel(self, timeout: float = 5.0) -> bool:
        """Ask the server to cancel this goal; True when it agreed (the goal then ends canceled)."""
        return self.goal_id in self.client._cancel(self.goal_id, timeout)


class ActionClient:
    """Sends goals to one action server; safe to use from inside callbacks, as service clients are.

    Feedback callbacks run on the client's helper thread, in the order the server sent them.
    """

    def __init__(self, node: Node, action_type: ActionKind, name: str) -> None:
        action_type = as_action_type(action_type)
        services, topics = _checked_endpoints(node, action_type, name, "client")
        self.node = node
        self.type = action_type
        self.name = name
        types = node.graph.types
        self._send_goal, self._cancel_goal, self._get_result = (
            Client(node, types.get_service(services[part][1]), services[part][0])
            for part in ("send_goal", "cancel_goal", "get_result"))
        self._lock = threading.Lock()
        self._serving = threading.RLock()  # one thread delivers at a time, in order
        self._handles: dict[bytes, ClientGoalHandle] = {}
        self._feedback = node.graph.open_reader(topics["feedback"][0], node.name, topics["feedback"][1],
                                                node.executor.wake)
        self._status = node.graph.open_reader(topics["status"][0], node.name, topics["status"][1], node.executor.wake)
        self._helper = _Helper(node, f"action-client:{name}", self._serve)
        self._helper.start()

    def _serve(self) -> None:
        """Deliver feedback and status; also called by ``result()``, so feedback sent before the
        goal ended has reached its callback when the result is returned."""
        with self._serving:
            self._deliver()

    def _deliver(self) -> None:
        while (message := self._feedback.try_take()) is not None:
            with self._lock:
                handle = self._handles.get(bytes(message.goal_id.uuid))
            if handle is not None and handle.feedback_cb is not None:
                try:
                    handle.feedback_cb(message.feedback)
                except Exception:
                    log.exception("action %s: a feedback callback raised", self.name)
        while (message := self._status.try_take()) is not None:
            with self._lock:
                for status in message.status_list:
                    handle = self._handles.get(bytes(status.goal_info.goal_id.uuid))
                    if handle is not None:
                        handle.status = GoalStatus(int(status.status))
                        if handle.status in _TERMINAL and handle._result is not None and handle._result.done():
                            del self._handles[handle.goal_id]  # its feedback all came before this status

    def _forget(self, goal_id: bytes) -> None:
        with self._lock:
            self._handles.pop(goal_id, None)

    def _wait(self, future: Future[Any], timeout: float | None, what: str) -> Any:
        deadline = None if timeout is None else time.monotonic() + timeout
        executor = self.node.executor
        while True:
            seen = executor.generation
            if future.done():
                return future.result()
            if self.node.graph.stop.is_set():
                reason = self.node.graph.stop_reason
                raise ActionError(f"action {self.name}: {what} never came: the graph is shutting down"
                                  + (f" because {reason}" if reason else ""))
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise ActionTimeoutError(f"action {self.name}: {what} did not come within {timeout:g} s; is its "
                                         "server node running (see `hetros graph`)?")
            executor.wait(seen, _TICK if left is None else min(left, _TICK))

    def send_goal_async(self, goal: Any, feedback_cb: Callable[[Any], object] | None = None,
                        goal_id: bytes | None = None) -> Future[ClientGoalHandle]:
        """Send ``goal`` without waiting: the future gives its handle once the server accepted or rejected it.
        ``goal_id`` (16 bytes) is made up when not given. Cancelling the future forgets the goal."""
        check_type(goal, typename_of(self.type.Goal), f"a goal of action {self.name}")
        goal._hetros_validate(goal, f"the goal of {self.name}")
        if goal_id is None:
            goal_id = os.urandom(16)
        elif len(goal_id) != 16:
            raise ActionError(f"a goal id must be 16 bytes, not {goal_id!r}")
        handle = ClientGoalHandle(self, goal_id, feedback_cb)
        with self._lock:
            self._handles[goal_id] = handle
        answered: Future[ClientGoalHandle] = Future()

        def on_answer(answer: Future[Any]) -> None:
            if not answered.set_running_or_notify_cancel():  # the sender gave up waiting
                self._forget(goal_id)
                return
            try:
                response = answer.result()
            except BaseException as exc:
                self._forget(goal_id)
                answered.set_exception(exc)
                return
            handle.accepted = bool(response.accepted)
            handle.stamp = response.stamp
            if not handle.accepted:
                self._forget(goal_id)
            else:
                handle.status = max(handle.status, ACCEPTED)
                handle._result = self._get_result.call_async(self.type.GetResult.Request(goal_id=uuid_message(goal_id)))
            answered.set_result(handle)
        try:
            self._send_goal.call_async(self.type.SendGoal.Request(goal_id=uuid_message(goal_id), goal=goal)) \
                .add_done_callback(on_answer)
        except BaseException:
            self._forget(goal_id)
            raise
        return answered

    def send_goal(self, goal: Any, feedback_cb: Callable[[Any], object] | None = None,
                  timeout: float = 10.0) -> ClientGoalHandle:
        """Send ``goal``; return its handle once the server accepted or rejected it (``handle.accepted``)."""
        goal_id = os.urandom(16)
        answered = self.send_goal_async(goal, feedback_cb, goal_id)
        try:
            handle: ClientGoalHandle = self._wait(answered, timeout, f"the answer to goal {_short(goal_id)}")
        except BaseException:
            answered.cancel()
            self._forget(goal_id)
            raise
        return handle

    def cancel_async(self, goal_id: bytes) -> Future[Any]:
        """Ask the server to cancel goal ``goal_id`` (all goals: 16 zero bytes); the future gives its
        ``action_msgs/srv/CancelGoal`` response."""
        types = registry()
        info = types.get("action_msgs/msg/GoalInfo")(goal_id=uuid_message(goal_id),
                                                     stamp=types.get("builtin_interfaces/msg/Time")())
        return self._cancel_goal.call_async(self._cancel_goal.srv_type.Request(goal_info=info))

    def _cancel(self, goal_id: bytes, timeout: float) -> set[bytes]:
        response = self._wait(self.cancel_async(goal_id), timeout, f"the answer to canceling {_short(goal_id)}")
        return {bytes(g.goal_id.uuid) for g in response.goals_canceling}

    def cancel_all(self, timeout: float = 5.0) -> int:
        """Ask the server to cancel every goal (any client's); return how many it agreed to cancel."""
        return len(self._cancel(bytes(16), timeout))

    def close(self) -> None:
        self._helper.close()
        for client in (self._send_goal, self._cancel_goal, self._get_result):
            client.close()
        self._feedback.close()
        self._status.close()
