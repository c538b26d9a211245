"""Hardware topics against fpgaDDS's Table I and II: simulated transfer times, Yosys resources.
See benchmarks/hetros_bench/hw.py."""

import sys

from hetros_bench.hw import main

sys.exit(main())
