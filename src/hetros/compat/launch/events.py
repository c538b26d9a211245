"""launch.events: the events a launch file emits. ``Shutdown`` is what an exit handler emits to end the
launch when a node exits (a ``required:`` node in hetros's project)."""

from __future__ import annotations

from typing import Any

from ._core import LaunchContext


class Event:
    name = "launch.events.Event"


class Shutdown(Event):
    name = "launch.events.Shutdown"

    def __init__(self, *, reason: Any = "reason not given", due_to_sigint: bool = False) -> None:
        self.reason = reason
        self.due_to_sigint = due_to_sigint

    def emitted(self, context: LaunchContext, where: str) -> None:
        context.note(where, "Shutdown emitted outside an event handler: the launch would end at once; ignored")


def matches_action(target_action: Any) -> Any:
    """A matcher for the events of one action (launch_ros's ChangeState uses it to name a lifecycle node)."""

    def matcher(action: Any) -> bool:
        return action is target_action

    matcher.target = target_action  # type: ignore[attr-defined]
    return matcher


__all__ = ["Event", "Shutdown", "matches_action"]
