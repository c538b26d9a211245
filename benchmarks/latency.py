"""Latency benchmark: hetros inproc and shm against CycloneDDS, iceoryx2, zenoh, dora-rs, rospy,
multiprocessing.Pipe and a plain numpy copy, in one run. See benchmarks/hetros_bench/latency.py."""

import sys

from hetros_bench.latency import main

sys.exit(main())
