"""launch.event_handlers: what a launch file does when its processes start or exit.

hetros's graph is static: every node starts with the launch, and a node's exit ends the launch when it
is ``required:``. So an exit handler that shuts the launch down makes its target required; the actions
of a start or exit handler start with the graph (noted, since their order changes nothing on reliable
topics); a handler given as a Python function of the event has no event to call it with, and is
refused naming its line."""

from __future__ import annotations

from typing import Any

from ._core import LaunchContext, LaunchDescriptionEntity, LaunchFileError


def _is_shutdown(entity: Any) -> bool:
    from .actions import EmitEvent, Shutdown
    from .events import Shutdown as ShutdownEvent

    return isinstance(entity, Shutdown) or (isinstance(entity, EmitEvent) and isinstance(entity.event, ShutdownEvent))


class EventHandler:
    def __init__(self, *, matcher: Any = None, entities: Any = None, handle_once: bool = False) -> None:
        self.matcher = matcher
        self.entities = entities
        self.handle_once = handle_once

    def _listed(self, value: Any, where: str) -> list[LaunchDescriptionEntity]:
        if value is None:
            return []
        if callable(value) and not isinstance(value, LaunchDescriptionEntity):
            raise LaunchFileError(f"{where}: {type(self).__name__} with a function of the event has no counterpart in "
                              "hetros (the graph is known before anything starts); give the actions as a list")
        return [value] if isinstance(value, LaunchDescriptionEntity) else list(value)

    def entities_now(self, context: LaunchContext, where: str) -> list[LaunchDescriptionEntity]:
        return self._listed(self.entities, where)


class _OnTarget(EventHandler):
    def __init__(self, target_action: Any, actions: Any) -> None:
        super().__init__()
        self.target_action = target_action
        self.actions = actions

    def _target_name(self) -> str:
        target = self.target_action
        return str(getattr(target, "node_name_given", None) or getattr(target, "name", None) or "any process")


class OnProcessStart(_OnTarget):
    def __init__(self, *, target_action: Any = None, on_start: Any = None, **kwargs: Any) -> None:
        super().__init__(target_action, on_start)

    def entities_now(self, context: LaunchContext, where: str) -> list[LaunchDescriptionEntity]:
        found = self._listed(self.actions, where)
        if found:
            context.note(where, f"OnProcessStart of {self._target_name()}: its actions start with the graph")
        return found


class OnProcessExit(_OnTarget):
    def __init__(self, *, target_action: Any = None, on_exit: Any = None, **kwargs: Any) -> None:
        super().__init__(target_action, on_exit)

    def entities_now(self, context: LaunchContext, where: str) -> list[LaunchDescriptionEntity]:
        found = self._listed(self.actions, where)
        if any(_is_shutdown(entity) for entity in found):
            if self.target_action is None:
                raise LaunchFileError(f"{where}: a shutdown on any process's exit: name target_action=, the node whose "
                                  "exit ends the launch")
            context.record("required", where, id=id(self.target_action))
        rest = [entity for entity in found if not _is_shutdown(entity)]
        if rest:
            context.note(where, f"OnProcessExit of {self._target_name()}: its actions start with the graph, not "
                                "after the exit")
        return rest


class OnExecutionComplete(OnProcessExit):
    def __init__(self, *, target_action: Any = None, on_completion: Any = None, **kwargs: Any) -> None:
        super().__init__(target_action=target_action, on_exit=on_completion)


class OnShutdown(EventHandler):
    def __init__(self, *, on_shutdown: Any = None, **kwargs: Any) -> None:
        super().__init__()
        self.on_shutdown = on_shutdown

    def entities_now(self, context: LaunchContext, where: str) -> list[LaunchDescriptionEntity]:
        context.note(where, "OnShutdown: its actions are not run by hetros (the launcher stops nodes in order)")
        return []


__all__ = ["EventHandler", "OnExecutionComplete", "OnProcessExit", "OnProcessStart", "OnShutdown"]
