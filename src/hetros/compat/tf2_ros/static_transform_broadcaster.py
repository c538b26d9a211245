"""tf2_ros.StaticTransformBroadcaster: publishes transforms that never change on /tf_static, transient_local
(latched in ROS 1), each message holding every static transform sent so far (by child frame), so a late
listener gets them all."""

from __future__ import annotations

from typing import Any

from ._endpoints import STATIC_PUBLISHER_QOS, STATIC_TOPIC, hetros_node, tf_message, tf_type


class StaticTransformBroadcaster:
    def __init__(self, node: Any = None, qos: Any = None, queue_size: int = 100) -> None:
        self._publisher = hetros_node(node).create_publisher(tf_type(), STATIC_TOPIC, qos=STATIC_PUBLISHER_QOS)
        self._sent: dict[str, Any] = {}

    def sendTransform(self, transform: Any) -> None:
        for one in list(transform) if isinstance(transform, list | tuple) else [transform]:
            self._sent[one.child_frame_id] = one
        self._publisher.publish(tf_message(list(self._sent.values())))

    send_transform = sendTransform


__all__ = ["StaticTransformBroadcaster"]
