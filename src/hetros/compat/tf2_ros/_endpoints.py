"""The topics tf2 lives on, opened on the hetros node of the calling code, whichever ROS it speaks.

/tf carries transforms that change (keep_last 100), /tf_static the ones that do not (transient_local, so
a listener that starts late still gets them): as tf2_ros gives them in ROS 1 (latched) and ROS 2."""

from __future__ import annotations

from typing import Any

from ..._qos import QoS
from ...msg import registry
from ...runtime import Node as HetrosNode
from ...runtime import bound_node

TF_TOPIC, STATIC_TOPIC = "/tf", "/tf_static"
TF_TYPE = "tf2_msgs/msg/TFMessage"
TF_QOS = QoS(history="keep_last", depth=100)
STATIC_QOS = QoS(history="keep_last", depth=100, durability="transient_local")
STATIC_PUBLISHER_QOS = QoS(history="keep_last", depth=1, durability="transient_local")


def hetros_node(node: Any) -> HetrosNode:
    """The hetros node under an rclpy node, or this thread's (rospy code, which names no node)."""
    inner = getattr(node, "_hetros", None)
    return inner if isinstance(inner, HetrosNode) else bound_node()


def tf_message(transforms: list[Any]) -> Any:
    return registry().get(TF_TYPE)(transforms=list(transforms))


def tf_type() -> Any:
    return registry().get(TF_TYPE)
