"""message_filters for rclpy and rospy code (``hetros.compat.message_filters``): the synchronizers emit
the sets Debian's python3-message-filters (the reference algorithm) emits, in its order, for three
inputs at 30/15/10 Hz with jitter and out-of-order arrivals; message_filters' own Python tests pass
unchanged (tests/data/upstream_message_filters); Cache, Chain and callbacks with extra arguments."""

from __future__ import annotations

import json
import random
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from hetros.compat.message_filters import ApproximateTimeSynchronizer, Cache, Chain, SimpleFilter, TimeSynchronizer
from hetros.msg import registry

REFERENCE = Path(__file__).resolve().parents[1] / "support" / "message_filters_reference.py"
UPSTREAM = Path(__file__).resolve().parents[1] / "data" / "upstream_message_filters"
_HAS_REFERENCE = Path("/usr/bin/python3").exists() and subprocess.run(
    ["/usr/bin/python3", "-c", "import message_filters, rospy"], capture_output=True, check=False).returncode == 0
SECOND = 1_000_000_000


def _stamped(ns: int) -> Any:
    message = registry().get("std_msgs/msg/Header")()
    holder = registry().get("geometry_msgs/msg/PointStamped")(header=message)
    holder.header.stamp.sec, holder.header.stamp.nanosec = divmod(ns, SECOND)
    return holder


def _arrivals(seed: int, rates: tuple[float, ...], seconds: float, drop: float = 0.0) -> list[list[int]]:
    """(input, stamp) in arrival order: each input at its rate with a few ms of jitter on the stamps, some
    dropped, each arriving 0-40 ms after its stamp."""
    rng = random.Random(seed)
    sent = []
    for index, rate in enumerate(rates):
        for k in range(int(seconds * rate)):
            if rng.random() < drop:
                continue
            stamp = round((k / rate + rng.gauss(0, 0.004)) * SECOND) + SECOND
            sent.append((stamp + rng.randrange(0, 40_000_000), index, stamp))
    return [[index, stamp] for _arrive, index, stamp in sorted(sent)]


def _ours(scenario: dict[str, Any]) -> list[list[int]]:
    inputs = [SimpleFilter() for _ in range(scenario["inputs"])]
    sync: SimpleFilter = ApproximateTimeSynchronizer(inputs, scenario["queue_size"], scenario["slop"]) \
        if scenario["kind"] == "approximate" else TimeSynchronizer(inputs, scenario["queue_size"])
    emitted: list[list[int]] = []
    sync.registerCallback(lambda *msgs: emitted.append([m.header.stamp.sec * SECOND + m.header.stamp.nanosec
                                                        for m in msgs]))
    for index, ns in scenario["arrivals"]:
        inputs[index].signalMessage(_stamped(ns))
    return emitted


def _reference(scenario: dict[str, Any]) -> list[list[int]]:
    done = subprocess.run(["/usr/bin/python3", str(REFERENCE)], input=json.dumps(scenario), capture_output=True,
                          text=True, check=True, timeout=120)
    emitted: list[list[int]] = json.loads(done.stdout)
    return emitted


@pytest.mark.skipif(not _HAS_REFERENCE, reason="Debian's python3-message-filters is not installed")
@pytest.mark.parametrize("seed", range(4))
def test_approximate_sync_of_three_rates_emits_the_reference_sets_in_order(seed: int) -> None:
    scenario = {"kind": "approximate", "queue_size": 10, "slop": 0.03, "inputs": 3,
                "arrivals": _arrivals(seed, (30.0, 15.0, 10.0), 6.0, drop=0.05)}
    ours, reference = _ours(scenario), _reference(scenario)
    assert len(reference) >= 20
    assert ours == reference


@pytest.mark.skipif(not _HAS_REFERENCE, reason="Debian's python3-message-filters is not installed")
def test_exact_sync_emits_the_reference_sets_in_order() -> None:
    rng = random.Random(7)
    arrivals = [[index, SECOND + k * 50_000_000] for k in range(60) for index in range(2) if rng.random() > 0.2]
    rng.shuffle(arrivals)
    scenario = {"kind": "exact", "queue_size": 5, "slop": 0.0, "inputs": 2, "arrivals": arrivals}
    ours, reference = _ours(scenario), _reference(scenario)
    assert reference and ours == reference


def test_a_cache_looks_up_by_time_and_a_chain_passes_through_its_filters() -> None:
    head = SimpleFilter()
    cache = Cache(head, cache_size=3)
    for k in range(5):
        head.signalMessage(_stamped(k * SECOND))
    assert [m.header.stamp.sec for m in cache.getInterval(0, 10)] == [2, 3, 4]
    assert cache.getElemAfterTime(2.5).header.stamp.sec == 3
    assert cache.getElemBeforeTime(2.5).header.stamp.sec == 2
    assert cache.getElemAfterTime(9) is None
    chain = Chain([Cache(cache_size=2), Cache(cache_size=1)])
    heard: list[tuple[int, str]] = []
    chain.registerCallback(lambda m, extra: heard.append((m.header.stamp.sec, extra)), "extra")
    chain.connectInput(head)
    head.signalMessage(_stamped(7 * SECOND))
    assert heard == [(7, "extra")]
    assert chain.getFilter(1).getLast().header.stamp.sec == 7  # type: ignore[attr-defined]


def test_message_filters_own_approximate_sync_test_passes_unchanged() -> None:
    done = subprocess.run([sys.executable, "-c", "import sys, pytest\nfrom hetros.compat import install\ninstall()\n"
                           "sys.exit(pytest.main(['-q', '-p', 'no:cacheprovider', *sys.argv[1:]]))",
                           str(UPSTREAM / "test_approxsync.py")], capture_output=True, text=True, timeout=120,
                          check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 passed" in done.stdout, done.stdout


def test_init_finds_the_topics_of_message_filters_subscribers(tmp_path: Path) -> None:
    from hetros.project._ros_scan import scan_ros_script

    code = tmp_path / "pairer.py"
    code.write_text(
        "import message_filters\nimport rospy\nfrom message_filters import Subscriber as Sub\n"
        "from sensor_msgs.msg import CameraInfo, Image\n\n"
        "rospy.init_node('pairer')\n"
        "a = message_filters.Subscriber('image', Image)\n"  # rospy's form: topic first
        "b = Sub(node, CameraInfo, '/camera_info', 5)\n")  # rclpy's form: node, type, topic, qos
    found = scan_ros_script(code, tmp_path, tmp_path)
    assert found.endpoints["subscribe"] == {"image": "sensor_msgs/msg/Image",
                                            "/camera_info": "sensor_msgs/msg/CameraInfo"}
