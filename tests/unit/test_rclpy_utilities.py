"""rclpy.utilities as ROS 2 nodes use it to parse their own command line (``sys.argv`` is the node's)."""

from __future__ import annotations

import pytest

from hetros.compat import install

install()

from rclpy.utilities import remove_ros_args, timeout_sec_to_nsec  # noqa: E402


@pytest.mark.parametrize(("args", "kept"), [
    (["talker_qos", "-n", "3"], ["talker_qos", "-n", "3"]),
    (["p", "--ros-args", "-r", "__node:=x", "--", "--reliable"], ["p", "--reliable"]),
    (["p", "--ros-args", "-p", "a:=1"], ["p"]),
    (["p", "-n", "2", "--ros-args", "-r", "a:=b", "--", "x", "--ros-args", "--log-level", "debug"],
     ["p", "-n", "2", "x"]),
])
def test_ros_args_are_removed_up_to_their_end(args: list[str], kept: list[str]) -> None:
    assert remove_ros_args(args=args) == kept


def test_timeouts_convert_as_rclpys() -> None:
    assert timeout_sec_to_nsec(None) == -1 and timeout_sec_to_nsec(-2) == -1
    assert timeout_sec_to_nsec(1.5) == 1_500_000_000
