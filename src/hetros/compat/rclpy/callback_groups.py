"""rclpy.callback_groups: accepted everywhere rclpy takes them. A hetros node runs its callbacks one at a
time (its executor), so a reentrant group runs them one at a time too; a callback may still wait on a
service or an action from inside, as hetros's clients wait without the executor."""

from __future__ import annotations


class CallbackGroup:
    def __init__(self) -> None:
        self.entities: list[object] = []

    def add_entity(self, entity: object) -> None:
        self.entities.append(entity)

    def has_entity(self, entity: object) -> bool:
        return entity in self.entities


class MutuallyExclusiveCallbackGroup(CallbackGroup):
    pass


class ReentrantCallbackGroup(CallbackGroup):
    pass
