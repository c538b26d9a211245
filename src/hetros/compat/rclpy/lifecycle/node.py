"""rclpy.lifecycle.node: ``LifecycleNode``, an rclpy node whose transitions hetros's state machine runs."""

from __future__ import annotations

from typing import Any, NamedTuple

from ...._errors import NodeError
from ....runtime import LIFECYCLE_LABELS, Lifecycle
from ..node import Node
from ..qos import QoSProfile
from .managed_entity import ManagedEntity, TransitionCallbackReturn
from .publisher import LifecyclePublisher

# rcl_lifecycle's ids: the shutdown transition from each primary state, and the callback of each transition state
_SHUTDOWN_FROM = {"unconfigured": 5, "inactive": 6, "active": 7}
_CALLBACKS = {"configuring": "on_configure", "cleaningup": "on_cleanup", "shuttingdown": "on_shutdown",
              "activating": "on_activate", "deactivating": "on_deactivate", "errorprocessing": "on_error"}


class LifecycleState(NamedTuple):
    label: str
    state_id: int


class LifecycleNodeMixin(ManagedEntity):
    """The lifecycle part of a node: its callbacks by transition state, and its managed entities (the
    lifecycle publishers among them), told of each transition by the default callbacks."""

    def __init__(self, *, enable_communication_interface: bool = True, callback_group: Any = None) -> None:
        if not isinstance(self, Node):
            raise TypeError("LifecycleNodeMixin needs rclpy's Node in the class's bases")
        self._managed_entities: set[ManagedEntity] = set()
        self._lifecycle: Lifecycle = self._hetros.manage(self._transition, self.get_fully_qualified_name())

    def _transition(self, state: int, started_from: int) -> int:
        name = _CALLBACKS[LIFECYCLE_LABELS[state]]
        result = getattr(self, name)(LifecycleState(LIFECYCLE_LABELS[started_from], started_from))
        if not isinstance(result, int) or result not in (97, 98, 99):
            raise TypeError(f"{name}() must return a TransitionCallbackReturn, not {result!r}")
        return int(result)

    def _trigger(self, transition_id: int) -> TransitionCallbackReturn:
        return TransitionCallbackReturn(self._lifecycle.trigger(transition_id))

    def trigger_configure(self) -> TransitionCallbackReturn:
        return self._trigger(1)

    def trigger_cleanup(self) -> TransitionCallbackReturn:
        return self._trigger(2)

    def trigger_activate(self) -> TransitionCallbackReturn:
        return self._trigger(3)

    def trigger_deactivate(self) -> TransitionCallbackReturn:
        return self._trigger(4)

    def trigger_shutdown(self) -> TransitionCallbackReturn:
        state = LIFECYCLE_LABELS[self._lifecycle.state]
        if state not in _SHUTDOWN_FROM:
            raise NodeError(f"{self._lifecycle.full_name}: shutdown is not possible from {state}")
        return self._trigger(_SHUTDOWN_FROM[state])

    def add_managed_entity(self, entity: ManagedEntity) -> None:
        if not isinstance(entity, ManagedEntity):
            raise TypeError("Expected a rclpy.lifecycle.ManagedEntity instance.")
        self._managed_entities.add(entity)

    def _entities_say(self, name: str, state: LifecycleState) -> TransitionCallbackReturn:
        for entity in list(self._managed_entities):
            result = getattr(entity, name)(state)
            if result != TransitionCallbackReturn.SUCCESS:
                return TransitionCallbackReturn(result)
        return TransitionCallbackReturn.SUCCESS

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self._entities_say("on_configure", state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self._entities_say("on_cleanup", state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self._entities_say("on_shutdown", state)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self._entities_say("on_activate", state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self._entities_say("on_deactivate", state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self._entities_say("on_error", state)

    def create_lifecycle_publisher(self, msg_type: type[Any], topic: str, qos_profile: QoSProfile | int, *,
                                   publisher_class: Any = None, **kwargs: Any) -> LifecyclePublisher:
        if publisher_class is not None:
            raise TypeError("create_publisher() got an unexpected keyword argument 'publisher_class'")
        assert isinstance(self, Node)
        plain = Node.create_publisher(self, msg_type, topic, qos_profile, **kwargs)
        publisher = LifecyclePublisher(self, plain._inner, msg_type, plain.topic_name)
        publisher.best_effort = plain.best_effort
        self._owned[self._owned.index(plain)] = publisher  # disabled until the next activation, as in rclpy
        self._managed_entities.add(publisher)
        return publisher

    def destroy_lifecycle_publisher(self, publisher: LifecyclePublisher) -> bool:
        self._managed_entities.discard(publisher)
        assert isinstance(self, Node)
        return self.destroy_publisher(publisher)


class LifecycleNode(LifecycleNodeMixin, Node):
    """A managed node: rclpy's Node with the lifecycle's callbacks, services and transition events."""

    def __init__(self, node_name: str, *, enable_communication_interface: bool = True, **kwargs: Any) -> None:
        Node.__init__(self, node_name, **kwargs)
        LifecycleNodeMixin.__init__(self, enable_communication_interface=enable_communication_interface)


__all__ = ["LifecycleNode", "LifecycleNodeMixin", "LifecycleState"]
