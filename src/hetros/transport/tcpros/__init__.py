"""ROS 1 interoperability: the master (so far; TCPROS and the slave API come next)."""

from ._master import DEFAULT_PORT, Master, MasterState

__all__ = ["DEFAULT_PORT", "Master", "MasterState"]
