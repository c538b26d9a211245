"""tf2_ros.TransformBroadcaster: publishes transforms on /tf (ROS 2: ``TransformBroadcaster(node)``; ROS 1:
``TransformBroadcaster()`` on the rospy node)."""

from __future__ import annotations

from typing import Any

from ..._qos import QoS
from ._endpoints import TF_QOS, TF_TOPIC, hetros_node, tf_message, tf_type


class TransformBroadcaster:
    def __init__(self, node: Any = None, qos: Any = None, queue_size: int = 100) -> None:
        depth = qos if isinstance(qos, int) else getattr(qos, "depth", None) or TF_QOS.depth
        self._publisher = hetros_node(node).create_publisher(tf_type(), TF_TOPIC,
                                                             qos=QoS(history="keep_last", depth=depth))

    def sendTransform(self, transform: Any) -> None:
        transforms = list(transform) if isinstance(transform, list | tuple) else [transform]
        self._publisher.publish(tf_message(transforms))

    send_transform = sendTransform


__all__ = ["TransformBroadcaster"]
