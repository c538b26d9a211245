"""rclpy.callback_groups, with rclpy's protocol: before a callback runs, its group is asked
(``can_execute``, ``beginning_execution``) and told when it ended (``ending_execution``). A hetros node
runs its callbacks one at a time, so the built-in groups matter only where rclpy code runs callbacks in
threads of its own (a custom executor's pool); a custom group (a token bucket, say) is obeyed as rclpy
obeys it: a timer it refuses skips that tick, a message it refuses is offered again shortly."""

from __future__ import annotations

import threading


class CallbackGroup:
    def __init__(self) -> None:
        self.entities: list[object] = []

    def add_entity(self, entity: object) -> None:
        self.entities.append(entity)

    def has_entity(self, entity: object) -> bool:
        return entity in self.entities

    def can_execute(self, entity: object) -> bool:
        return True

    def beginning_execution(self, entity: object) -> bool:
        return True

    def ending_execution(self, entity: object) -> None:
        return None


class MutuallyExclusiveCallbackGroup(CallbackGroup):
    """One callback of the group at a time."""

    def __init__(self) -> None:
        super().__init__()
        self._lock = threading.Lock()
        self._active = False

    def can_execute(self, entity: object) -> bool:
        return not self._active

    def beginning_execution(self, entity: object) -> bool:
        with self._lock:
            if self._active:
                return False
            self._active = True
            return True

    def ending_execution(self, entity: object) -> None:
        with self._lock:
            self._active = False


class ReentrantCallbackGroup(CallbackGroup):
    pass


BUILT_IN_GROUPS = (CallbackGroup, MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup)
