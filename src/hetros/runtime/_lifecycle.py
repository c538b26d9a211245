"""A managed node's state machine, as ROS 2's lifecycle (rcl_lifecycle) defines it: four primary states,
six transition states, the transitions between them with their ids and labels, the five services
(``change_state``, ``get_state``, ``get_available_states``, ``get_available_transitions``,
``get_transition_graph``) and the ``transition_event`` topic, under the node's full name.

A node's code supplies what happens in each transition state (rclpy's ``on_configure`` and the rest,
:mod:`hetros.compat.rclpy.lifecycle`); the project's ``lifecycle:`` says which state the launch brings
the node to once it is made, as launch_ros's ChangeState events do."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple

from .._errors import NodeError
from ..msg import registry
from ..plan import LIFECYCLE_EVENTS, LIFECYCLE_SERVICES, LIFECYCLE_TRANSITIONS

if TYPE_CHECKING:
    from ..msg import ServiceType
    from ._node import Node

UNCONFIGURED, INACTIVE, ACTIVE, FINALIZED = 1, 2, 3, 4
CONFIGURING, CLEANINGUP, SHUTTINGDOWN, ACTIVATING, DEACTIVATING, ERRORPROCESSING = 10, 11, 12, 13, 14, 15
LABELS = {0: "unknown", UNCONFIGURED: "unconfigured", INACTIVE: "inactive", ACTIVE: "active",
          FINALIZED: "finalized", CONFIGURING: "configuring", CLEANINGUP: "cleaningup",
          SHUTTINGDOWN: "shuttingdown", ACTIVATING: "activating", DEACTIVATING: "deactivating",
          ERRORPROCESSING: "errorprocessing"}
# what a transition state's callback returns (lifecycle_msgs/Transition's TRANSITION_CALLBACK_*)
SUCCESS, FAILURE, ERROR = 97, 98, 99
RESULT_LABELS = {SUCCESS: "transition_success", FAILURE: "transition_failure", ERROR: "transition_error"}


class Transition(NamedTuple):
    id: int
    label: str
    start: int
    goal: int


# the transitions one asks for (the plan's table), from a primary state to the transition state its label runs
_DOING = {"configure": CONFIGURING, "cleanup": CLEANINGUP, "activate": ACTIVATING, "deactivate": DEACTIVATING,
          "shutdown": SHUTTINGDOWN}
_STATE_IDS = {label: state for state, label in LABELS.items()}
REQUESTED = tuple(Transition(tid, label, _STATE_IDS[start], _DOING[label])
                  for tid, (label, start, _) in LIFECYCLE_TRANSITIONS.items())
# the transitions a callback's result takes, from a transition state: (state, result) -> transition
_RESULTS = {(CONFIGURING, SUCCESS): (10, INACTIVE), (CONFIGURING, FAILURE): (11, UNCONFIGURED),
            (CONFIGURING, ERROR): (12, ERRORPROCESSING), (CLEANINGUP, SUCCESS): (20, UNCONFIGURED),
            (CLEANINGUP, FAILURE): (21, INACTIVE), (CLEANINGUP, ERROR): (22, ERRORPROCESSING),
            (ACTIVATING, SUCCESS): (30, ACTIVE), (ACTIVATING, FAILURE): (31, INACTIVE),
            (ACTIVATING, ERROR): (32, ERRORPROCESSING), (DEACTIVATING, SUCCESS): (40, INACTIVE),
            (DEACTIVATING, FAILURE): (41, ACTIVE), (DEACTIVATING, ERROR): (42, ERRORPROCESSING),
            (SHUTTINGDOWN, SUCCESS): (50, FINALIZED), (SHUTTINGDOWN, FAILURE): (51, FINALIZED),
            (SHUTTINGDOWN, ERROR): (52, ERRORPROCESSING), (ERRORPROCESSING, SUCCESS): (60, UNCONFIGURED),
            (ERRORPROCESSING, FAILURE): (61, FINALIZED), (ERRORPROCESSING, ERROR): (62, FINALIZED)}
RESULTED = tuple(Transition(tid, RESULT_LABELS[result], state, goal)
                 for (state, result), (tid, goal) in _RESULTS.items())
# the transitions that bring an unconfigured node to each state the project may ask for
_PATH = {"unconfigured": (), "inactive": (1,), "active": (1, 3)}

# what runs in a transition state: (that state, the state the transition started from) -> a result
TransitionCallback = Callable[[int, int], int]


def from_functions(**callbacks: Callable[[], bool | None] | None) -> TransitionCallback:
    """The transition callback of hetros's own API: ``on_configure`` and the rest by name, each taking
    nothing and refusing its transition by returning False (raising is the transition's error)."""
    by_state = {CONFIGURING: "on_configure", ACTIVATING: "on_activate", DEACTIVATING: "on_deactivate",
                CLEANINGUP: "on_cleanup", SHUTTINGDOWN: "on_shutdown", ERRORPROCESSING: "on_error"}

    def run(state: int, started_from: int) -> int:
        callback = callbacks.get(by_state[state])
        return SUCCESS if callback is None or callback() is not False else FAILURE
    return run


def _srv(name: str) -> ServiceType:
    return registry().get_service(LIFECYCLE_SERVICES[name])


def _msg(name: str) -> Any:
    return registry().get(f"lifecycle_msgs/msg/{name}")


class Lifecycle:
    """One managed node's state and transitions. Transitions run in the node's executor thread (a
    service request, a launch's autostart) or in the thread that asks (``trigger`` from the node's own
    code), one at a time, as rclpy's do."""

    def __init__(self, node: Node, full_name: str, callback: TransitionCallback) -> None:
        self._node = node
        self.full_name = full_name
        self._callback = callback
        self.state = UNCONFIGURED
        self._events: Any = None
        planned = node.graph.plan.nodes.get(node.name) if node.graph.plan is not None else None
        topic = f"{full_name}/{LIFECYCLE_EVENTS[0]}"
        if planned is not None and topic in planned.publish:
            self._events = node.create_publisher(_msg("TransitionEvent"), topic)
        handlers: dict[str, Callable[[Any], Any]] = {
            "change_state": self._on_change_state, "get_state": self._on_get_state,
            "get_available_states": self._on_get_available_states,
            "get_available_transitions": self._on_get_available_transitions,
            "get_transition_graph": self._on_get_transition_graph}
        self.services: dict[str, tuple[ServiceType, Callable[[Any], Any]]] = {
            f"{full_name}/{name}": (_srv(name), handler) for name, handler in handlers.items()}
        planned_services = planned.services if planned is not None else {}
        for service, (srv_type, handler) in self.services.items():
            if service in planned_services:
                node.create_service(srv_type, service, handler)
        if planned is not None and planned.lifecycle in _PATH:
            steps = list(_PATH[planned.lifecycle])

            def autostart() -> None:  # once the node's code is past its constructor, as launch's events come
                for step in steps:
                    if self.trigger(step) != SUCCESS:
                        node.log.error(f"the launch's transition {self.label_of(step)!r} of {full_name} failed; "
                                       f"it stays {LABELS[self.state]}")
                        return
            node.executor.add_timer(time.monotonic(), autostart)

    # -- transitions -----------------------------------------------------------------------

    @staticmethod
    def label_of(transition_id: int) -> str:
        return next((t.label for t in (*REQUESTED, *RESULTED) if t.id == transition_id), str(transition_id))

    def available(self) -> list[Transition]:
        return [t for t in REQUESTED if t.start == self.state]

    def transition_by_label(self, label: str) -> int | None:
        return next((t.id for t in self.available() if t.label == label), None)

    def trigger(self, transition_id: int) -> int:
        """Take ``transition_id`` from the current state, run its callback and take the transition its
        result names; the result (SUCCESS, FAILURE, ERROR). A transition not available here is an ERROR,
        logged as rclpy logs it."""
        requested = next((t for t in self.available() if t.id == transition_id), None)
        if requested is None:
            self._node.log.error(f"Unable to start transition {transition_id} from current state "
                                 f"({self.state}, '{LABELS[self.state]}')")
            return ERROR
        started_from = self.state
        self._move(requested)
        result = self._run(requested.goal, started_from)
        self._resulted(result)
        if result == ERROR:  # the error state's own callback decides where the node goes from there
            self._resulted(self._run(ERRORPROCESSING, started_from))
        return result

    def _run(self, state: int, started_from: int) -> int:
        try:
            result = int(self._callback(state, started_from))
        except Exception as exc:
            self._node.log.error(f"{LABELS[state]}: the transition callback raised {type(exc).__name__}: {exc}")
            return ERROR
        if result not in RESULT_LABELS:
            raise NodeError(f"{self.full_name}: a transition callback must return a TransitionCallbackReturn "
                            f"(SUCCESS, FAILURE or ERROR), not {result!r}")
        return result

    def _resulted(self, result: int) -> None:
        tid, goal = _RESULTS[(self.state, result)]
        self._move(Transition(tid, RESULT_LABELS[result], self.state, goal))

    def _move(self, transition: Transition) -> None:
        self.state = transition.goal
        if self._events is not None:
            self._events.publish(_msg("TransitionEvent")(
                timestamp=time.time_ns(), transition=_msg("Transition")(id=transition.id, label=transition.label),
                start_state=_msg("State")(id=transition.start, label=LABELS[transition.start]),
                goal_state=_msg("State")(id=transition.goal, label=LABELS[transition.goal])))

    # -- the services ------------------------------------------------------------------------

    def _on_change_state(self, request: Any) -> Any:
        transition_id = int(request.transition.id)
        if request.transition.label:
            found = self.transition_by_label(str(request.transition.label))
            if found is None:
                return _srv("change_state").Response(success=False)
            transition_id = found
        return _srv("change_state").Response(success=self.trigger(transition_id) == SUCCESS)

    def _on_get_state(self, request: Any) -> Any:
        return _srv("get_state").Response(current_state=_msg("State")(id=self.state, label=LABELS[self.state]))

    def _on_get_available_states(self, request: Any) -> Any:
        return _srv("get_available_states").Response(available_states=[
            _msg("State")(id=state, label=label) for state, label in LABELS.items() if state])

    @staticmethod
    def _described(transitions: list[Transition]) -> list[Any]:
        return [_msg("TransitionDescription")(
            transition=_msg("Transition")(id=t.id, label=t.label),
            start_state=_msg("State")(id=t.start, label=LABELS[t.start]),
            goal_state=_msg("State")(id=t.goal, label=LABELS[t.goal])) for t in transitions]

    def _on_get_available_transitions(self, request: Any) -> Any:
        return _srv("get_available_transitions").Response(available_transitions=self._described(self.available()))

    def _on_get_transition_graph(self, request: Any) -> Any:
        return _srv("get_transition_graph").Response(
            available_transitions=self._described([*REQUESTED, *RESULTED]))


LIFECYCLE_LABELS = LABELS

__all__ = ["ACTIVE", "ERROR", "FAILURE", "INACTIVE", "LABELS", "LIFECYCLE_LABELS", "SUCCESS", "Lifecycle",
           "TransitionCallback", "from_functions"]
