"""ROS 1 benchmark: one-way latency over TCPROS for rospy -> rospy, rospy -> hetros, hetros -> rospy and
hetros -> hetros in one run, pinned to separate CPUs. See benchmarks/hetros_bench/ros1.py."""

import sys

from hetros_bench.ros1 import main

sys.exit(main())
