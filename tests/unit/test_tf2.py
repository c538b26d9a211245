"""tf2 for rclpy and rospy code (``hetros.compat.tf2_ros``, ``tf2_py``, ``tf2_geometry_msgs``): tf2's own
Python tests pass unchanged (tests/data/upstream_tf2), and what they do not reach is held here: waits that
end at their timeout, the cache's length, static frames at every time, the batch point transform, and the
transforms tf2 refuses to store."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hetros.compat import install
from hetros.compat.tf2_py import BufferCore
from hetros.msg import registry

UPSTREAM = Path(__file__).resolve().parents[1] / "data" / "upstream_tf2"
SECOND = 1_000_000_000


def test_tf2s_own_buffer_and_geometry_msgs_tests_pass_unchanged() -> None:
    done = subprocess.run([sys.executable, "-c", "import sys, pytest\nfrom hetros.compat import install\ninstall()\n"
                           "sys.exit(pytest.main(['-q', '-p', 'no:cacheprovider', *sys.argv[1:]]))",
                           str(UPSTREAM / "test_buffer.py"), str(UPSTREAM / "test_tf2_geometry_msgs.py")],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "7 passed" in done.stdout, done.stdout


def _transform(parent: str, child: str, seconds: float, x: float = 1.0, w: float = 1.0) -> object:
    message = registry().get("geometry_msgs/msg/TransformStamped")()
    message.header.frame_id, message.child_frame_id = parent, child
    message.header.stamp.sec, message.header.stamp.nanosec = divmod(round(seconds * SECOND), SECOND)
    message.transform.translation.x = x
    message.transform.rotation.w = w
    return message


def test_a_lookup_waits_until_its_timeout_and_no_longer() -> None:
    install()
    import rclpy.duration
    import tf2_ros

    buffer = tf2_ros.Buffer()
    started = time.monotonic()
    assert buffer.can_transform("a", "b", rclpy.time.Time(), rclpy.duration.Duration(seconds=0.3)) is False
    assert 0.25 <= time.monotonic() - started < 5
    with pytest.raises(tf2_ros.LookupException, match='"a" passed to lookupTransform argument target_frame'):
        buffer.lookup_transform("a", "b", rclpy.time.Time(), rclpy.duration.Duration(seconds=0.1))


def test_the_cache_keeps_its_length_behind_the_newest_and_statics_hold_at_every_time() -> None:
    core = BufferCore(2.0)
    for second in range(6):
        core.set_transform(_transform("map", "base", second, x=second), "test")
    core.set_transform_static(_transform("base", "laser", 0, x=0.5), "test")
    pose, stamp = core.lookup_pose("map", "base", 4.5)
    assert pose[0] == pytest.approx(4.5) and stamp == 4_500_000_000
    ok, why = core.can_lookup("map", "base", 2.5)  # older than 5 s - 2 s
    assert not ok and "into the past" in why
    pose, _ = core.lookup_pose("map", "laser", 0)  # the latest common time: the moving frame's newest
    assert pose[0] == pytest.approx(5.5)
    assert not core.accept(_transform("map", "map", 6), "test", static=False)  # tf2's TF_SELF_TRANSFORM
    assert not core.accept(_transform("map", "base", 7, w=2.0), "test", static=False)  # denormalized
    assert not core.accept(_transform("map", "base", 5), "test", static=False)  # repeated stamp


def test_a_batch_of_points_moves_in_one_numpy_product() -> None:
    install()
    import tf2_geometry_msgs

    transform = _transform("a", "b", 0, x=1.0)
    half_turn = np.sqrt(0.5)
    transform.transform.rotation.z, transform.transform.rotation.w = half_turn, half_turn  # type: ignore[attr-defined]
    points = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    moved = tf2_geometry_msgs.transform_points(points, transform)
    assert np.allclose(moved, [[1.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    one = registry().get("geometry_msgs/msg/PointStamped")()
    one.point.x, one.point.y = 0.0, 2.0
    single = tf2_geometry_msgs.do_transform_point(one, transform)
    assert np.allclose([single.point.x, single.point.y, single.point.z], moved[1])
    with pytest.raises(ValueError, match=r"points must be an array of shape \(N, 3\)"):
        tf2_geometry_msgs.transform_points(np.zeros(3), transform)


def test_the_libraries_benchmark_runs_hetros_side_on_a_small_scenario() -> None:
    hetros_bench = pytest.importorskip("hetros_bench.libraries")
    plan = hetros_bench.scenario(quick=True)
    plan["tf"]["queries"] = plan["tf"]["queries"][:20]
    plan["sync"]["arrivals"] = plan["sync"]["arrivals"][:60]
    for part in ("tf", "sync", "cv"):
        plan[part]["repeat"] = 1
    figures = hetros_bench.ours(plan)
    assert set(figures) == set(hetros_bench.LABELS) and all(v > 0 for v in figures.values())
