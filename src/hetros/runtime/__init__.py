"""Runtime: node API, per-node executor, per-process graph, launcher."""

from ._graph import Graph
from ._host import Host, resolve
from ._launcher import Launcher, LaunchResult, launch
from ._log import setup_logging
from ._node import Client, Node, Publisher, Service, Subscription, Timer

__all__ = [
    "Client",
    "Graph",
    "Host",
    "LaunchResult",
    "Launcher",
    "Node",
    "Publisher",
    "Service",
    "Subscription",
    "Timer",
    "launch",
    "resolve",
    "setup_logging",
]
