"""The plan: the architecture graph, computed once before anything runs.

``hetros.project`` produces it from the project file; ``hetros.runtime`` executes it.
Neither depends on the other: both depend on this package.
"""

from ._plan import (
    LAUNCHER,
    SERVICE_QOS,
    ChannelKind,
    ChannelPlan,
    EdgePlan,
    NodePlan,
    Plan,
    TargetPlan,
    TransportKind,
    process_name,
    reply_channel,
    request_channel,
    service_of,
)

__all__ = [
    "LAUNCHER",
    "SERVICE_QOS",
    "ChannelKind",
    "ChannelPlan",
    "EdgePlan",
    "NodePlan",
    "Plan",
    "TargetPlan",
    "TransportKind",
    "process_name",
    "reply_channel",
    "request_channel",
    "service_of",
]
