"""Hardware topics against fpgaDDS's Table I and II: simulated transfer times, Yosys resources.
See hetros/bench/hw.py."""

import sys

from hetros.bench.hw import main

sys.exit(main())
