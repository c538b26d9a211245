"""Runtime: node API, per-node executor, per-process graph, the host of a process' nodes."""

from ._action import ActionClient, ActionServer, ClientGoalHandle, GoalStatus, ServerGoalHandle
from ._graph import Graph
from ._host import Host, resolve
from ._log import setup_logging
from ._node import Client, Node, Publisher, Replies, Service, Subscription, Timer

__all__ = [
    "ActionClient",
    "ActionServer",
    "Client",
    "ClientGoalHandle",
    "GoalStatus",
    "Graph",
    "Host",
    "Node",
    "Publisher",
    "Replies",
    "ServerGoalHandle",
    "Service",
    "Subscription",
    "Timer",
    "resolve",
    "setup_logging",
]
