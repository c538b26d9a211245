"""rclpy.lifecycle.publisher: a publisher that publishes only while its node is active."""

from __future__ import annotations

from typing import Any

from ..node import Publisher
from .managed_entity import SimpleManagedEntity


class LifecyclePublisher(SimpleManagedEntity, Publisher):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        SimpleManagedEntity.__init__(self)
        Publisher.__init__(self, *args, **kwargs)

    @SimpleManagedEntity.when_enabled
    def publish(self, msg: Any) -> None:
        Publisher.publish(self, msg)


__all__ = ["LifecyclePublisher"]
