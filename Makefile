# Two commands on a fresh machine: `make run` and `make test`.
VENV    ?= .venv
PY      := $(VENV)/bin/python
PIP     := $(VENV)/bin/pip
STAMP   := $(VENV)/.installed
TSTAMP  := $(VENV)/.installed-test
PYTHON  ?= python3

BSTAMP  := $(VENV)/.installed-bench
# The real peers of the tests and benchmarks, from Debian: ROS 1 (rospy, roscpp, actionlib, the
# ros* tools), Icarus Verilog (runs the fpga targets' exported Verilog), Verilator (co-simulates fpga
# targets under `hetros launch`), iproute2 (the network namespaces of the multi-host tests), and ROS 1's
# rosbag, tf2, message_filters and cv_bridge (the reference peers of hetros's bags and libraries);
# installed when we may
PEER_DEBS := iverilog verilator ros-core python3-rospy python3-rostopic python3-rosnode python3-rosparam python3-rosservice \
             python3-std-msgs python3-sensor-msgs python3-std-srvs python3-actionlib libroscpp-dev libstd-srvs-dev \
             python3-rosbag python3-tf2-ros python3-message-filters python3-cv-bridge g++ pkg-config iproute2 \
             clang-14 libclang-rt-14-dev
define install_peer_debs
	@if { [ ! -x /usr/bin/rostopic ] || [ ! -d /usr/lib/python3/dist-packages/std_srvs ] || \
	      [ ! -f /usr/include/std_srvs/SetBool.h ] || [ ! -d /usr/lib/python3/dist-packages/actionlib ] || \
	      [ ! -d /usr/lib/python3/dist-packages/rosbag ] || [ ! -d /usr/lib/python3/dist-packages/tf2_py ] || \
	      [ ! -d /usr/lib/python3/dist-packages/message_filters ] || [ ! -d /usr/lib/python3/dist-packages/cv_bridge ] || \
	      ! command -v iverilog > /dev/null || ! command -v verilator > /dev/null || ! command -v g++ > /dev/null || ! command -v ip > /dev/null || \
	      ! command -v clang-14 > /dev/null; } && \
	    [ "$$(id -u)" = 0 ]; then \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $(PEER_DEBS) > /dev/null; fi
endef


.PHONY: install install-rtl install-examples install-test install-bench run test coverage fast fuzz lint bench bench-quick clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --quiet --upgrade pip

$(STAMP): pyproject.toml setup.py src/hetros/msg/_ccdr.c src/hetros/transport/shm/_cslot.c | $(PY)
	$(PIP) install --quiet -e .
	touch $@

install: $(STAMP)

# fpga targets' tools (hetros hw ..., hetros bench hw): Amaranth, Yosys; about 130 MB
install-rtl: | $(PY)
	$(PIP) install --quiet -e '.[rtl]'

# every example beyond the default one: scikit-learn's digits, scipy
install-examples: | $(PY)
	$(PIP) install --quiet -e '.[examples]'

$(TSTAMP): pyproject.toml benchmarks/pyproject.toml setup.py src/hetros/msg/_ccdr.c src/hetros/transport/shm/_cslot.c Makefile | $(PY)
	$(PIP) install --quiet -e '.[test]' -e benchmarks
	$(install_peer_debs)
	touch $(STAMP) $@

install-test: $(TSTAMP)

# The benchmark's peers: pip extras, Debian's rospy + rosmaster, and Cyclone's native ddsperf
# (cyclonedds-tools) when we may install them.
$(BSTAMP): pyproject.toml benchmarks/pyproject.toml setup.py src/hetros/msg/_ccdr.c src/hetros/transport/shm/_cslot.c Makefile | $(PY)
	$(PIP) install --quiet -e '.[bench]' -e benchmarks
	$(install_peer_debs)
	@if ! command -v ddsperf > /dev/null && [ "$$(id -u)" = 0 ]; then \
		DEBIAN_FRONTEND=noninteractive apt-get install -y -qq cyclonedds-tools > /dev/null; fi
	touch $(STAMP) $@

install-bench: $(BSTAMP)

bench: install-bench
	$(VENV)/bin/hetros bench latency

bench-quick: install-bench
	$(VENV)/bin/hetros bench latency --quick

run: install
	$(VENV)/bin/hetros graph examples/lane_following/project.yaml
	$(VENV)/bin/hetros launch examples/lane_following/project.yaml --duration 40 --node-times

# the examples are type-checked as users' code is: against the stubs of their own message packages
# (`hetros msg stubs`), each folder on its own (every example has a nodes.py)
lint: install-test
	$(VENV)/bin/ruff check src tests examples benchmarks fuzz
	$(VENV)/bin/mypy --strict src benchmarks/hetros_bench
	$(VENV)/bin/hetros msg stubs examples/*/msg -o out/typings > /dev/null
	for example in examples/*/; do \
		MYPYPATH=out/typings:examples/inverse_kinematics $(VENV)/bin/mypy --strict $$example || exit 1; done

# the fast loop of CONTRIBUTING.md: lint, types, the unit and conformance suites (no launch, no simulator)
fast: install-test
	$(VENV)/bin/ruff check src tests examples benchmarks fuzz
	$(VENV)/bin/mypy --strict src benchmarks/hetros_bench
	$(VENV)/bin/pytest -q -p no:cacheprovider -m "not rtl and not slow" tests/unit tests/conformance

# simulators, Yosys and nextpnr do minutes of work each on a slow machine: their phase's limit is that work's
RTL_TIMEOUT = 1200

# the conformance suite once more on the pure-Python path (what runs where no C compiler is), then every
# suite on two workers; untraced: tracing the unit, conformance and fuzz suites for a coverage figure cost two
# of the 20 minutes the default run must stay under on 2 cores (`make coverage` gives the figure)
test: lint
	HETROS_PURE_PYTHON=1 $(VENV)/bin/pytest -q -p no:cacheprovider tests/conformance
	$(VENV)/bin/pytest -q -p no:cacheprovider -n 2 -m "not rtl" tests/unit tests/conformance tests/fuzz
	$(VENV)/bin/pytest -q -p no:cacheprovider -n 2 -m rtl --timeout $(RTL_TIMEOUT) tests/unit
	$(MAKE) --no-print-directory fuzz FUZZ_RUNS=$(FUZZ_SHORT)
	$(VENV)/bin/pytest -q -p no:cacheprovider -n 2 --dist loadfile -m "not machine_wide" tests/integration tests/interop
	$(VENV)/bin/pytest -q -p no:cacheprovider -m machine_wide tests/integration tests/interop

# the C parsers of untrusted bytes, coverage-guided under AddressSanitizer and UBSan (fuzz/c_parsers.py): the
# long run is 1,000,000 executions per target; make test runs FUZZ_SHORT. Needs clang-14 and its sanitizer
# runtimes (installed with the test peers as root); without them it says so and skips.
FUZZ_RUNS = 1000000
FUZZ_SHORT = 20000
FUZZ_TARGETS = cdr ros1 slot
fuzz: install-test
	@if ! command -v clang-14 > /dev/null; then echo "fuzz: clang-14 is not installed (make install-test as root installs it); skipped"; exit 0; fi; \
	mkdir -p out; preload="$$($(VENV)/bin/python -c 'import atheris; print(atheris.path())')/asan_with_fuzzer.so"; \
	for target in $(FUZZ_TARGETS); do \
		echo "fuzz $$target: $(FUZZ_RUNS) runs under ASan and UBSan"; \
		ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
		LD_PRELOAD="$$preload" $(VENV)/bin/python fuzz/c_parsers.py $$target -runs=$(FUZZ_RUNS) -print_final_stats=1 \
			> out/fuzz-$$target.log 2>&1 || { tail -40 out/fuzz-$$target.log; exit 1; }; \
		grep -E "^stat::number_of_executed_units|^Done" out/fuzz-$$target.log | tr '\n' ' '; echo; \
	done

# the share of src/hetros's lines the unit, conformance and fuzz suites run (a launch's workers are never traced)
coverage: install-test
	$(VENV)/bin/pytest -q -p no:cacheprovider -n 2 --cov=hetros --cov-report= tests/unit tests/conformance tests/fuzz
	@$(VENV)/bin/coverage report --format=total | xargs printf "coverage: %s%% of src/hetros's lines ran in the test process\n"

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache
