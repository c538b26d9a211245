"""launch_ros.event_handlers: a managed node's transitions, as the launch's own steps."""

from __future__ import annotations

from typing import Any

from ..launch import LaunchContext, LaunchDescriptionEntity
from ..launch.event_handlers import EventHandler


class OnStateTransition(EventHandler):
    """What a launch does when a managed node reaches a state: its entities (most often the next
    ``ChangeState``) are taken as the launch's next steps, so an autostart chain brings the node to its
    final state when the graph starts."""

    def __init__(self, *, entities: Any = None, target_lifecycle_node: Any = None, transition: Any = None,
                 start_state: Any = None, goal_state: Any = None, matcher: Any = None, **kwargs: Any) -> None:
        super().__init__(entities=entities)
        self.target_lifecycle_node = target_lifecycle_node
        self.goal_state = goal_state

    def entities_now(self, context: LaunchContext, where: str) -> list[LaunchDescriptionEntity]:
        return self._listed(self.entities, where)


__all__ = ["OnStateTransition"]
