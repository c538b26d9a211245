"""ROS 1 interoperability: the master, the slave API, TCPROS connections and the type mapping."""

from ...msg import ros1_store
from ._actions import (
    ABORTED,
    ACTIVE,
    PENDING,
    PREEMPTED,
    PREEMPTING,
    RECALLED,
    REJECTED,
    SUCCEEDED,
    TERMINAL,
    Ros1ActionType,
)
from ._endpoints import ROSRPC_CLIENT, Ros1ServiceCaller, Ros1ServiceServer, Ros1Writer, open_ros1_reader
from ._master import DEFAULT_PORT, Master, MasterState
from ._peer import Ros1Peer, Ros1Publication, Ros1Subscription, get_ros1_parameter, receive_frames
from ._stream import Ros1StreamReader, SocketWaiter
from ._transport import Ros1Transport
from ._types import Ros1NativeType, Ros1ServiceType, Ros1Type, ros1_name

__all__ = [
    "ABORTED",
    "ACTIVE",
    "DEFAULT_PORT",
    "PENDING",
    "PREEMPTED",
    "PREEMPTING",
    "RECALLED",
    "REJECTED",
    "ROSRPC_CLIENT",
    "SUCCEEDED",
    "TERMINAL",
    "Master",
    "MasterState",
    "Ros1ActionType",
    "Ros1NativeType",
    "Ros1Peer",
    "Ros1Publication",
    "Ros1ServiceCaller",
    "Ros1ServiceServer",
    "Ros1ServiceType",
    "Ros1StreamReader",
    "Ros1Subscription",
    "Ros1Transport",
    "Ros1Type",
    "Ros1Writer",
    "SocketWaiter",
    "get_ros1_parameter",
    "open_ros1_reader",
    "receive_frames",
    "ros1_name",
    "ros1_store",
]
