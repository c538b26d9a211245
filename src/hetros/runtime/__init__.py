"""Runtime: node API, per-node executor, per-process graph, the host of a process' nodes."""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports
from ._clock import Clock, Duration, SimulatedClock, Time, check_hz, check_period
from ._entities import (
    PROFILE_VARIABLE,
    Client,
    HandlingStats,
    Publisher,
    Replies,
    Service,
    Subscription,
    Timer,
    check_type,
)
from ._graph import Graph
from ._host import Host, resolve
from ._log import setup_logging
from ._matched import IncompatibleQosStatus, MatchedStatus
from ._node import NODE_TIMES_VARIABLE, Node
from ._parameters import (
    ParameterAccess,
    ProjectParameters,
    from_value_message,
    kind_of,
    listed,
    to_value_message,
    type_change_problem,
)
from ._qos_events import DeadlineMissedStatus, LivelinessChangedStatus, LivelinessLostStatus, MessageLostStatus
from ._service_events import EVENT_TOPIC_SUFFIX, EventKind, Introspection, client_gid

if TYPE_CHECKING:
    from ._action import ActionClient, ActionServer, ClientGoalHandle, GoalStatus, ServerGoalHandle, uuid_message
    from ._clock import Ticker
    from ._executor import AdaptiveSpin, yield_to_callbacks
    from ._lifecycle import LIFECYCLE_LABELS, Lifecycle
    from ._log import RCLPY_CONSOLE, ROSPY_CONSOLE, log_to_file, node_logger, stop_logging_to
    from ._ros_main import bound_node, mark_shut_down, ros_main, shut_down
    from ._taps import TapSink, check_rate, header_stamp


# shared with other packages, loaded on first use (a worker must not pay for what it does not run)
_LAZY = {
    "ActionClient": "._action",
    "ActionServer": "._action",
    "ClientGoalHandle": "._action",
    "GoalStatus": "._action",
    "Lifecycle": "._lifecycle",
    "LIFECYCLE_LABELS": "._lifecycle",
    "ServerGoalHandle": "._action",
    "AdaptiveSpin": "._executor",
    "yield_to_callbacks": "._executor",
    "RCLPY_CONSOLE": "._log",
    "ROSPY_CONSOLE": "._log",
    "TapSink": "._taps",
    "header_stamp": "._taps",
    "Ticker": "._clock",
    "bound_node": "._ros_main",
    "mark_shut_down": "._ros_main",
    "shut_down": "._ros_main",
    "check_rate": "._taps",
    "log_to_file": "._log",
    "node_logger": "._log",
    "ros_main": "._ros_main",
    "stop_logging_to": "._log",
    "uuid_message": "._action",
}


__getattr__ = lazy_exports(__name__, _LAZY)


__all__ = [
    "EVENT_TOPIC_SUFFIX",
    "LIFECYCLE_LABELS",
    "NODE_TIMES_VARIABLE",
    "PROFILE_VARIABLE",
    "RCLPY_CONSOLE",
    "ROSPY_CONSOLE",
    "ActionClient",
    "ActionServer",
    "AdaptiveSpin",
    "Client",
    "ClientGoalHandle",
    "Clock",
    "DeadlineMissedStatus",
    "Duration",
    "EventKind",
    "GoalStatus",
    "Graph",
    "HandlingStats",
    "Host",
    "IncompatibleQosStatus",
    "Introspection",
    "Lifecycle",
    "LivelinessChangedStatus",
    "LivelinessLostStatus",
    "MatchedStatus",
    "MessageLostStatus",
    "Node",
    "ParameterAccess",
    "ProjectParameters",
    "Publisher",
    "Replies",
    "ServerGoalHandle",
    "Service",
    "SimulatedClock",
    "Subscription",
    "TapSink",
    "Ticker",
    "Time",
    "Timer",
    "bound_node",
    "check_hz",
    "check_period",
    "check_rate",
    "check_type",
    "client_gid",
    "from_value_message",
    "header_stamp",
    "kind_of",
    "listed",
    "log_to_file",
    "mark_shut_down",
    "node_logger",
    "resolve",
    "ros_main",
    "setup_logging",
    "shut_down",
    "stop_logging_to",
    "to_value_message",
    "type_change_problem",
    "uuid_message",
    "yield_to_callbacks",
]
