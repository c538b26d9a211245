"""Managed nodes: the state machine ROS 2's lifecycle defines (states, transitions, callback results,
error processing), its services, and hetros's and rclpy's ways of writing one."""

from __future__ import annotations

from typing import Any

import pytest

from hetros import NodeError
from hetros.msg import registry
from hetros.runtime import Graph, Node
from hetros.runtime._lifecycle import ACTIVE, ERROR, FAILURE, FINALIZED, INACTIVE, SUCCESS, UNCONFIGURED


def _call(node: Node, service: str, **fields: Any) -> Any:
    assert node.lifecycle is not None
    srv_type, handler = node.lifecycle.services[f"/{node.name}/{service}"]
    return handler(registry().get(f"{srv_type.name}_Request")(**fields))


def test_the_primary_states_and_their_transitions() -> None:
    calls: list[str] = []
    node = Node("talker", Graph.standalone())
    lifecycle = node.create_lifecycle(on_configure=lambda: calls.append("configure"),
                                      on_activate=lambda: calls.append("activate"))
    assert lifecycle.state == UNCONFIGURED
    assert [t.label for t in lifecycle.available()] == ["configure", "shutdown"]
    assert lifecycle.trigger(1) == SUCCESS and lifecycle.state == INACTIVE
    assert lifecycle.trigger(3) == SUCCESS and lifecycle.state == ACTIVE
    assert calls == ["configure", "activate"]
    assert [(t.id, t.label) for t in lifecycle.available()] == [(4, "deactivate"), (7, "shutdown")]
    assert lifecycle.trigger(1) == ERROR and lifecycle.state == ACTIVE  # not available from active
    assert lifecycle.trigger(7) == SUCCESS and lifecycle.state == FINALIZED
    assert lifecycle.available() == []


def test_a_refusing_callback_keeps_the_state_and_a_raising_one_goes_through_error_processing() -> None:
    node = Node("talker", Graph.standalone())
    refuse = [True]

    def configure() -> bool:
        if refuse[0]:
            return False
        raise ValueError("broken")

    lifecycle = node.create_lifecycle(on_configure=configure, on_error=lambda: None)
    assert lifecycle.trigger(1) == FAILURE and lifecycle.state == UNCONFIGURED
    refuse[0] = False
    assert lifecycle.trigger(1) == ERROR
    assert lifecycle.state == UNCONFIGURED  # errorprocessing, whose on_error succeeded


def test_the_services_answer_as_rcl_lifecycle_does() -> None:
    node = Node("talker", Graph.standalone())
    node.create_lifecycle()
    assert _call(node, "get_state").current_state.label == "unconfigured"
    transition = registry().get("lifecycle_msgs/msg/Transition")
    assert _call(node, "change_state", transition=transition(label="configure")).success
    assert not _call(node, "change_state", transition=transition(label="deactivate")).success
    assert _call(node, "change_state", transition=transition(id=3)).success
    state = _call(node, "get_state").current_state
    assert (state.id, state.label) == (ACTIVE, "active")
    available = _call(node, "get_available_transitions").available_transitions
    assert [(t.transition.label, t.start_state.label, t.goal_state.label) for t in available] == [
        ("deactivate", "active", "deactivating"), ("shutdown", "active", "shuttingdown")]
    graph = _call(node, "get_transition_graph").available_transitions
    assert len(graph) == 25  # 7 asked for, 18 taken by results
    states = _call(node, "get_available_states").available_states
    assert [s.label for s in states][:4] == ["unconfigured", "inactive", "active", "finalized"]


def test_a_node_is_managed_once() -> None:
    node = Node("talker", Graph.standalone())
    node.create_lifecycle()
    with pytest.raises(NodeError, match="managed node already"):
        node.create_lifecycle()
