"""ROS 1 interoperability: the master, the slave API, TCPROS connections and the type mapping."""

from ._master import DEFAULT_PORT, Master, MasterState
from ._peer import Ros1Peer, Ros1Publication, Ros1Subscription, get_ros1_parameter
from ._types import Ros1ServiceType, Ros1Type, ros1_name

__all__ = ["DEFAULT_PORT", "Master", "MasterState", "Ros1Peer", "Ros1Publication", "Ros1ServiceType",
           "Ros1Subscription", "Ros1Type",
           "get_ros1_parameter", "ros1_name"]
