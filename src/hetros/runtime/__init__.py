"""Runtime: node API, per-node executor, per-process graph, launcher."""

from ._graph import Graph
from ._host import Host, resolve
from ._launcher import Launcher, LaunchResult, launch
from ._log import setup_logging
from ._node import Client, Node, Publisher, Service, Subscription, Timer
from ._plan import ChannelPlan, EdgePlan, NodePlan, Plan, TargetPlan

__all__ = [
    "ChannelPlan",
    "Client",
    "EdgePlan",
    "Graph",
    "Host",
    "LaunchResult",
    "Launcher",
    "Node",
    "NodePlan",
    "Plan",
    "Publisher",
    "Service",
    "Subscription",
    "TargetPlan",
    "Timer",
    "launch",
    "resolve",
    "setup_logging",
]
