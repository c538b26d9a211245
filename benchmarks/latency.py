"""Latency benchmark: hetros inproc and shm against CycloneDDS, iceoryx2, zenoh, dora-rs, rospy,
multiprocessing.Pipe and a plain numpy copy, in one run. See hetros/bench/latency.py."""

import sys

from hetros.bench.latency import main

sys.exit(main())
