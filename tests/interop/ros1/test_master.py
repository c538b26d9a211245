"""`hetros master` against stock ROS 1 from Debian: rospy nodes, rostopic, rosnode, rosparam, rosservice."""

from __future__ import annotations

import subprocess
import sys
import time
import xmlrpc.client
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from tests.support.ros1 import LISTENER, ROS_PYTHON, TALKER, needs_ros1, run_ros, stop

pytestmark = needs_ros1


@contextmanager
def _talking(env: dict[str, str], tmp_path: Path) -> Iterator[None]:
    """A stock rospy talker on /chatter while the block runs; listener.py beside it."""
    (tmp_path / "talker.py").write_text(TALKER)
    (tmp_path / "listener.py").write_text(LISTENER)
    talker = subprocess.Popen([ROS_PYTHON, str(tmp_path / "talker.py")], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        yield
    finally:
        stop(talker)


def test_rospy_nodes_and_ros_tools_work_against_hetros_master(master: tuple[str, dict[str, str]],
                                                              tmp_path: Path) -> None:
    uri, env = master
    with _talking(env, tmp_path):
        listened = run_ros(env, ROS_PYTHON, str(tmp_path / "listener.py"))
        assert listened.startswith("got 5 hello "), listened
        assert "/chatter" in run_ros(env, "rostopic", "list").split()
        assert run_ros(env, "rostopic", "type", "/chatter").strip() == "std_msgs/String"
        assert "data: \"hello" in run_ros(env, "rostopic", "echo", "-n", "1", "/chatter")
        assert "/talker" in run_ros(env, "rosnode", "list").split()
        assert run_ros(env, "rosparam", "get", "/talker/rate").strip() == "20"
        run_ros(env, "rosparam", "set", "/robot/wheels", "[1, 2]")
        assert run_ros(env, "rosparam", "get", "/robot/wheels").split() == ["-", "1", "-", "2"]
        assert "/robot/wheels" in run_ros(env, "rosparam", "list").split()
        run_ros(env, "rosparam", "delete", "/robot/wheels")
        assert "/talker/get_loggers" in run_ros(env, "rosservice", "list").split()
        assert "loggers:" in run_ros(env, "rosservice", "call", "/talker/get_loggers")
        state = xmlrpc.client.ServerProxy(uri).getSystemState("/test")
        assert state[0] == 1
        assert ["/chatter", ["/talker"]] in state[2][0]


def test_a_rospy_node_that_exits_disappears_from_the_graph(master: tuple[str, dict[str, str]],
                                                          tmp_path: Path) -> None:
    """rospy unregisters at shutdown with one ``system.multicall``; stock roscore serves it."""
    uri, env = master
    with _talking(env, tmp_path):
        assert run_ros(env, ROS_PYTHON, str(tmp_path / "listener.py")).startswith("got 5 hello ")
        deadline = time.monotonic() + 10
        while "/listener" in run_ros(env, "rosnode", "list").split():
            assert time.monotonic() < deadline, "the exited listener is still in rosnode list"
            time.sleep(0.2)
        subscribers = {topic: nodes for topic, nodes in xmlrpc.client.ServerProxy(uri).getSystemState("/t")[2][1]}
        assert "/listener" not in subscribers.get("/chatter", [])
        calls = xmlrpc.client.MultiCall(xmlrpc.client.ServerProxy(uri))
        calls.getUri("/t")
        calls.lookupNode("/t", "/nobody")
        first, second = calls().results  # type: ignore[attr-defined]
        assert first[0][0] == 1 and second[0][0] == -1


def test_a_node_registered_again_under_its_name_shuts_the_old_one_down(master: tuple[str, dict[str, str]],
                                                                       tmp_path: Path) -> None:
    _uri, env = master
    (tmp_path / "talker.py").write_text(TALKER)
    first = subprocess.Popen([ROS_PYTHON, str(tmp_path / "talker.py")], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    time.sleep(3)
    second = subprocess.Popen([ROS_PYTHON, str(tmp_path / "talker.py")], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        first.wait(20)  # ROS 1 semantics: the master tells the old node to shut down
        assert second.poll() is None
    finally:
        for proc in (first, second):
            stop(proc)


def test_a_taken_port_is_refused_with_what_to_do(master: tuple[str, dict[str, str]]) -> None:
    uri, _env = master
    port = uri.rsplit(":", 1)[1].rstrip("/")
    proc = subprocess.run([sys.executable, "-m", "hetros", "master", "--port", port],
                          capture_output=True, text=True, timeout=30, check=False)
    assert proc.returncode != 0
    assert f"cannot serve a ROS master on 127.0.0.1:{port}" in proc.stderr
    assert "choose another --port" in proc.stderr


ROSOUT = Path("/usr/lib/rosout/rosout")
LOGGER = """
import rospy
rospy.init_node("chatty")
rate = rospy.Rate(10)
while not rospy.is_shutdown():
    rospy.loginfo("hello from rospy")
    rate.sleep()
"""


def test_a_roscpp_node_works_against_hetros_master(master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    """Debian's rosout is a roscpp node: it registers, subscribes to /rosout and republishes."""
    if not ROSOUT.exists():
        pytest.skip("Debian's rosout (roscpp) is not installed")
    _uri, env = master
    (tmp_path / "chatty.py").write_text(LOGGER)
    rosout = subprocess.Popen([str(ROSOUT)], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    chatty = subprocess.Popen([ROS_PYTHON, str(tmp_path / "chatty.py")], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        echoed = run_ros(env, "rostopic", "echo", "-n", "1", "/rosout_agg", timeout=60)
        assert "hello from rospy" in echoed and "/chatty" in echoed
        assert "/rosout" in run_ros(env, "rosnode", "list").split()
    finally:
        for proc in (chatty, rosout):
            stop(proc)
