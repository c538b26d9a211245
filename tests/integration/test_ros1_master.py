"""`hetros master` against stock ROS 1 from Debian: rospy nodes, rostopic, rosnode, rosparam, rosservice."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import textwrap
import time
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

ROS_PYTHON = "/usr/bin/python3"


def _has_rospy() -> bool:
    try:
        return subprocess.run([ROS_PYTHON, "-c", "import rospy, rostopic, rosparam, rosservice, rosnode"],
                              capture_output=True, timeout=30, check=False).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


pytestmark = pytest.mark.skipif(not _has_rospy(), reason="Debian's python3-rospy and ROS tools are not installed "
                                                          "(`make test` installs them when run as root)")


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture
def master() -> Iterator[tuple[str, dict[str, str]]]:
    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "hetros", "master", "--port", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    uri = f"http://127.0.0.1:{port}/"
    deadline = time.monotonic() + 20
    while True:
        try:
            xmlrpc.client.ServerProxy(uri).getPid("/test")
            break
        except OSError:
            if time.monotonic() > deadline or proc.poll() is not None:
                proc.kill()
                raise AssertionError(f"hetros master did not come up: {proc.communicate()[0]}") from None
            time.sleep(0.1)
    env = dict(os.environ, ROS_MASTER_URI=uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME="/tmp/hetros-test-ros-home")
    env.pop("PYTHONPATH", None)
    yield uri, env
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()


TALKER = textwrap.dedent("""
    import rospy
    from std_msgs.msg import String
    rospy.init_node("talker")
    rospy.set_param("~rate", 20)
    pub = rospy.Publisher("/chatter", String, queue_size=10)
    rate = rospy.Rate(20)
    i = 0
    while not rospy.is_shutdown():
        pub.publish(String(data="hello %d" % i))
        i += 1
        rate.sleep()
""")

LISTENER = textwrap.dedent("""
    import sys, time, rospy
    from std_msgs.msg import String
    got = []
    rospy.init_node("listener")
    rospy.Subscriber("/chatter", String, lambda m: got.append(m.data))
    start = time.time()
    while len(got) < 5 and time.time() - start < 20:
        time.sleep(0.05)
    print("got", len(got), got[-1] if got else "")
""")


def _ros(env: dict[str, str], *args: str, timeout: float = 30) -> str:
    proc = subprocess.run(list(args), env=env, capture_output=True, text=True, timeout=timeout, check=False)
    assert proc.returncode == 0, f"{' '.join(args)} failed: {proc.stdout}{proc.stderr}"
    return proc.stdout


def test_rospy_nodes_and_ros_tools_work_against_hetros_master(master: tuple[str, dict[str, str]],
                                                              tmp_path: Path) -> None:
    uri, env = master
    (tmp_path / "talker.py").write_text(TALKER)
    (tmp_path / "listener.py").write_text(LISTENER)
    talker = subprocess.Popen([ROS_PYTHON, str(tmp_path / "talker.py")], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        listened = _ros(env, ROS_PYTHON, str(tmp_path / "listener.py"))
        assert listened.startswith("got 5 hello "), listened
        assert "/chatter" in _ros(env, "rostopic", "list").split()
        assert _ros(env, "rostopic", "type", "/chatter").strip() == "std_msgs/String"
        assert "data: \"hello" in _ros(env, "rostopic", "echo", "-n", "1", "/chatter")
        assert "/talker" in _ros(env, "rosnode", "list").split()
        assert _ros(env, "rosparam", "get", "/talker/rate").strip() == "20"
        _ros(env, "rosparam", "set", "/robot/wheels", "[1, 2]")
        assert _ros(env, "rosparam", "get", "/robot/wheels").split() == ["-", "1", "-", "2"]
        assert "/robot/wheels" in _ros(env, "rosparam", "list").split()
        _ros(env, "rosparam", "delete", "/robot/wheels")
        assert "/talker/get_loggers" in _ros(env, "rosservice", "list").split()
        assert "loggers:" in _ros(env, "rosservice", "call", "/talker/get_loggers")
        state = xmlrpc.client.ServerProxy(uri).getSystemState("/test")
        assert state[0] == 1
        assert ["/chatter", ["/talker"]] in state[2][0]
    finally:
        talker.terminate()
        talker.wait(10)


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
            proc.terminate()
            proc.wait(10)


def test_a_taken_port_is_refused_with_what_to_do(master: tuple[str, dict[str, str]]) -> None:
    uri, _env = master
    port = uri.rsplit(":", 1)[1].rstrip("/")
    proc = subprocess.run([sys.executable, "-m", "hetros", "master", "--port", port],
                          capture_output=True, text=True, timeout=30, check=False)
    assert proc.returncode != 0
    assert f"cannot serve a ROS master on 127.0.0.1:{port}" in proc.stderr
    assert "choose another --port" in proc.stderr
