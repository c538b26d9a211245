"""rclpy.topic_endpoint_info: what a graph query tells of one endpoint of a topic."""

from __future__ import annotations

import enum
from typing import Any

from .qos import from_hetros


class TopicEndpointTypeEnum(enum.IntEnum):
    INVALID = 0
    PUBLISHER = 1
    SUBSCRIPTION = 2


class TopicEndpointInfo:
    def __init__(self, *, node_name: str = "", node_namespace: str = "", topic_type: str = "",
                 endpoint_type: TopicEndpointTypeEnum = TopicEndpointTypeEnum.INVALID, qos: Any = None) -> None:
        self.node_name = node_name
        self.node_namespace = node_namespace
        self.topic_type = topic_type
        self.endpoint_type = endpoint_type
        self.endpoint_gid: list[int] = []
        self.qos_profile = from_hetros(qos) if qos is not None else None

    def __str__(self) -> str:
        return (f"Node name: {self.node_name}\nNode namespace: {self.node_namespace}\nTopic type: {self.topic_type}\n"
                f"Endpoint type: {self.endpoint_type.name}\nQoS profile: {self.qos_profile}")


__all__ = ["TopicEndpointInfo", "TopicEndpointTypeEnum"]
