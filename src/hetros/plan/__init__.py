"""The plan: the architecture graph, computed once before anything runs.

``hetros.project`` produces it from the project file; ``hetros.runtime`` executes it.
Neither depends on the other: both depend on this package.
"""

from ._names import join_namespace, resolve_name
from ._plan import (
    ACTION_PREFIX,
    CLOCK_PREFIX,
    CLOCK_TOPIC,
    CLOCK_TYPE,
    GATEWAY_PREFIX,
    LAUNCHER,
    ROS1_TRANSPORT,
    ROS2_BRIDGE,
    SERVICE_QOS,
    TRANSPORT_ORDER,
    ChannelKind,
    ChannelPlan,
    EdgePlan,
    HostPlan,
    NodePlan,
    Plan,
    TargetPlan,
    TransportKind,
    action_endpoints,
    action_topic_qos,
    gateway_node,
    process_name,
    reply_channel,
    request_channel,
    service_of,
)

__all__ = [
    "ACTION_PREFIX",
    "CLOCK_PREFIX",
    "CLOCK_TOPIC",
    "CLOCK_TYPE",
    "GATEWAY_PREFIX",
    "LAUNCHER",
    "ROS1_TRANSPORT",
    "ROS2_BRIDGE",
    "SERVICE_QOS",
    "TRANSPORT_ORDER",
    "ChannelKind",
    "ChannelPlan",
    "EdgePlan",
    "HostPlan",
    "NodePlan",
    "Plan",
    "TargetPlan",
    "TransportKind",
    "action_endpoints",
    "action_topic_qos",
    "gateway_node",
    "join_namespace",
    "process_name",
    "reply_channel",
    "request_channel",
    "resolve_name",
    "service_of",
]
