"""rospy nodes, unchanged, under `hetros launch`: the ros_tutorials talker/listener and add_two_ints
server/client (tests/data/ros_tutorials, copied as they are) across two processes, and a stock
Debian rospy listener hearing the unchanged talker through the ROS 1 bridge."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import yaml

from tests.support.ros1 import ROS_PYTHON, free_port, needs_ros1

TUTORIALS = Path(__file__).resolve().parents[1] / "data" / "ros_tutorials"
RUN = f"{TUTORIALS}/rospy_tutorials"


def launch(tmp_path: Path, project: dict[str, object], duration: float,
           env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    path = tmp_path / "project.yaml"
    path.write_text(yaml.safe_dump({"targets": {"a": {"kind": "process"}, "b": {"kind": "process"}}, **project}))
    environment = dict(env or os.environ, PYTHONPATH=f"{RUN}/001_talker_listener")
    checked = subprocess.run([sys.executable, "-m", "hetros", "check", str(path)], capture_output=True, text=True,
                             env=environment, timeout=120, check=False)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    return subprocess.run([sys.executable, "-m", "hetros", "launch", str(path), "--duration", str(duration)],
                          capture_output=True, text=True, env=environment, timeout=120, check=False, cwd=tmp_path)


def test_the_talker_and_listener(tmp_path: Path) -> None:
    done = launch(tmp_path, {"name": "rospy_talker_listener", "nodes": {
        "talker": {"run": "talker:talker", "target": "a", "publish": {"/chatter": "std_msgs/msg/String"}},
        "listener": {"run": "listener:listener", "target": "b", "subscribe": {"/chatter": "std_msgs/msg/String"}},
    }}, 2.5)
    assert done.returncode == 0, done.stderr
    said = re.findall(r"\[talker_\d+_\d+\]: (hello world [\d.]+)", done.stderr)
    heard = re.findall(r"\[listener_\d+_\d+\]: /listener_\d+_\d+I heard (hello world [\d.]+)", done.stderr)
    assert len(said) >= 15 and heard[:10] == said[:10], done.stderr
    assert "Traceback" not in done.stderr


def test_the_add_two_ints_server_and_client(tmp_path: Path) -> None:
    services = {"/add_two_ints": "rospy_tutorials/srv/AddTwoInts"}
    done = launch(tmp_path, {"name": "rospy_add_two_ints", "messages": [str(TUTORIALS / "msg")], "nodes": {
        "add_two_ints_server": {"run": f"{RUN}/005_add_two_ints/add_two_ints_server", "target": "a",
                                "services": services},
        "add_two_ints_client": {"run": f"{RUN}/005_add_two_ints/add_two_ints_client", "args": ["3", "4"],
                                "target": "b", "required": True, "clients": services},
    }}, 30)
    assert done.returncode == 0, done.stderr
    assert "Requesting 3+4\n" in done.stdout and "3 + 4 = 7\n" in done.stdout, done.stdout + done.stderr
    assert done.stdout.count("Returning [3 + 4 = 7]\n") == 2  # the simplified and the formal call
    assert "Traceback" not in done.stderr


@needs_ros1
def test_a_stock_rospy_listener_hears_the_unchanged_talker(tmp_path: Path) -> None:
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}/", ROS_HOSTNAME="127.0.0.1")
    master = subprocess.Popen([sys.executable, "-m", "hetros", "master", "--port", str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    listener = None
    try:
        time.sleep(1.0)
        listener = subprocess.Popen([ROS_PYTHON, f"{RUN}/001_talker_listener/listener.py"], env=env, text=True,
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        done = launch(tmp_path, {"name": "rospy_talker_ros1", "nodes": {
            "talker": {"run": "talker:talker", "target": "a", "publish": {"/chatter": "std_msgs/msg/String"}},
        }, "external": {"ros1": {"export": ["/chatter"]}}}, 6, env)
        assert done.returncode == 0, done.stderr
    finally:
        if listener is not None:
            listener.terminate()
        master.terminate()
        master.wait(10)
    assert listener is not None
    heard, _ = listener.communicate(timeout=30)
    assert re.search(r"I heard hello world [\d.]+", heard), heard
