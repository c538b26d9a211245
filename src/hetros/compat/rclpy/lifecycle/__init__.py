"""rclpy.lifecycle, as hetros serves it: managed nodes (``LifecycleNode``), their transition callbacks,
lifecycle publishers that publish only while active, and managed entities; the state machine and the
five lifecycle services are hetros's (:class:`hetros.runtime.Lifecycle`), under the node's full name."""

from .managed_entity import ManagedEntity, SimpleManagedEntity, TransitionCallbackReturn
from .node import LifecycleNode, LifecycleNodeMixin, LifecycleState
from .publisher import LifecyclePublisher

Node = LifecycleNode
NodeMixin = LifecycleNodeMixin
State = LifecycleState
Publisher = LifecyclePublisher

__all__ = [
    "LifecycleNode",
    "LifecycleNodeMixin",
    "LifecyclePublisher",
    "LifecycleState",
    "ManagedEntity",
    "Node",
    "NodeMixin",
    "Publisher",
    "SimpleManagedEntity",
    "State",
    "TransitionCallbackReturn",
]
