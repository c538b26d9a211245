"""DDS benchmark: hetros's DDS transport (ROS 2 endpoints and edges between hosts) against the raw
cyclonedds binding (fastest and stock paths) and Cyclone's native ddsperf, in one run, pinned to
separate CPUs. See benchmarks/hetros_bench/dds.py."""

import sys

from hetros_bench.dds import main

sys.exit(main())
