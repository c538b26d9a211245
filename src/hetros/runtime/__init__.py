"""Runtime: node API, per-node executor, per-process graph, the host of a process' nodes."""

from ._action import ActionClient, ActionServer, ClientGoalHandle, GoalStatus, ServerGoalHandle
from ._clock import Clock, Duration, SimulatedClock, Time
from ._entities import Client, Publisher, Replies, Service, Subscription, Timer
from ._graph import Graph
from ._host import Host, resolve
from ._log import setup_logging
from ._node import NODE_TIMES_VARIABLE, Node
from ._qos_events import DeadlineMissedStatus, LivelinessChangedStatus

__all__ = [
    "NODE_TIMES_VARIABLE",
    "ActionClient",
    "ActionServer",
    "Client",
    "ClientGoalHandle",
    "Clock",
    "DeadlineMissedStatus",
    "Duration",
    "GoalStatus",
    "Graph",
    "Host",
    "LivelinessChangedStatus",
    "Node",
    "Publisher",
    "Replies",
    "ServerGoalHandle",
    "Service",
    "SimulatedClock",
    "Subscription",
    "Time",
    "Timer",
    "resolve",
    "setup_logging",
]
