"""Runtime: node API, per-node executor, per-process graph, the host of a process' nodes."""

from ._graph import Graph
from ._host import Host, resolve
from ._log import setup_logging
from ._node import Client, Node, Publisher, Service, Subscription, Timer

__all__ = [
    "Client",
    "Graph",
    "Host",
    "Node",
    "Publisher",
    "Service",
    "Subscription",
    "Timer",
    "resolve",
    "setup_logging",
]
