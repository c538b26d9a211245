"""launch_ros.events.lifecycle: ``ChangeState``, a transition a launch asks of a managed node."""

from __future__ import annotations

from typing import Any

from ...launch import LaunchContext, LaunchFileError


class ChangeState:
    name = "launch_ros.events.lifecycle.ChangeState"

    def __init__(self, *, lifecycle_node_matcher: Any, transition_id: int) -> None:
        self.lifecycle_node_matcher = lifecycle_node_matcher
        self.transition_id = transition_id

    def emitted(self, context: LaunchContext, where: str) -> None:
        target = getattr(self.lifecycle_node_matcher, "target", None)
        if target is None:
            raise LaunchFileError(f"{where}: ChangeState needs lifecycle_node_matcher=matches_action(node), the node "
                              "it changes")
        context.record("transition", where, id=id(target), transition=int(self.transition_id))


class StateTransition:
    name = "launch_ros.events.lifecycle.StateTransition"


__all__ = ["ChangeState", "StateTransition"]
