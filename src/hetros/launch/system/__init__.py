"""The nodes the planner adds to a graph, which users never write: the fpga targets' gateways (and the
board surface they drive), the ROS 1 and ROS 2 bridges. Each is named in ``hetros.plan.SYSTEM_NODES``."""
