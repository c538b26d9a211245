"""The libraries around a node (tf2, message_filters, cv_bridge): hetros's against Debian's ROS 1 ones in one
run. See benchmarks/hetros_bench/libraries.py."""

import sys

from hetros_bench.libraries import main

sys.exit(main())
