"""rclpy nodes, unchanged, under `hetros launch`: the ros2/examples minimal publishers, subscribers,
services and clients (tests/data/ros2_examples, copied as they are), across two processes, printing
what they print under ROS 2."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

RCLPY = Path(__file__).resolve().parents[1] / "data" / "ros2_examples" / "rclpy"


def launch(tmp_path: Path, nodes: dict[str, dict[str, object]], packages: list[Path], duration: float,
           topics: dict[str, object] | None = None) -> subprocess.CompletedProcess[str]:
    """Check, then launch, a two-process project of the given nodes (code found on ``packages``)."""
    project = tmp_path / "project.yaml"
    project.write_text(yaml.safe_dump({"name": "rclpy_examples",
                                       "targets": {"a": {"kind": "process"}, "b": {"kind": "process"}},
                                       "nodes": nodes, "topics": topics or {}}))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(str(p) for p in packages))
    checked = subprocess.run([sys.executable, "-m", "hetros", "check", str(project)], capture_output=True,
                             text=True, env=env, timeout=120, check=False)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    return subprocess.run([sys.executable, "-m", "hetros", "launch", str(project), "--duration", str(duration)],
                          capture_output=True, text=True, env=env, timeout=120, check=False, cwd=tmp_path)


@pytest.mark.parametrize(("publisher", "subscriber"), [
    ("publisher_member_function", "subscriber_member_function"),
    ("publisher_old_school", "subscriber_old_school"),
    ("publisher_local_function", "subscriber_lambda"),
])
def test_the_minimal_publishers_and_subscribers(tmp_path: Path, publisher: str, subscriber: str) -> None:
    topics = RCLPY / "topics"
    done = launch(tmp_path, {
        "minimal_publisher": {"run": f"examples_rclpy_minimal_publisher.{publisher}:main", "target": "a",
                              "publish": {"/topic": "std_msgs/msg/String"}},
        "minimal_subscriber": {"run": f"examples_rclpy_minimal_subscriber.{subscriber}:main", "target": "b",
                               "subscribe": {"/topic": "std_msgs/msg/String"}},
    }, [topics / "minimal_publisher", topics / "minimal_subscriber"], 2.2,
        {"/topic": {"history": "keep_last", "depth": 10}})  # rclpy's create_publisher(String, 'topic', 10)
    assert done.returncode == 0, done.stderr
    published = re.findall(r"\[minimal_publisher\]: (.*)", done.stderr)
    heard = re.findall(r"\[minimal_subscriber\]: (.*)", done.stderr)
    assert published[:3] == [f'Publishing: "Hello World: {i}"' for i in range(3)], done.stderr
    assert heard[:3] == [f'I heard: "Hello World: {i}"' for i in range(3)], done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize(("server", "client", "client_name"), [
    ("service", "client", "minimal_client"),
    ("service_member_function", "client_async", "minimal_client_async"),
    ("service", "client_async_member_function", "minimal_client_async"),
    ("service_member_function", "client_async_callback", "minimal_client"),
])
def test_the_minimal_services_and_clients(tmp_path: Path, server: str, client: str, client_name: str) -> None:
    services = RCLPY / "services"
    done = launch(tmp_path, {
        "minimal_service": {"run": f"examples_rclpy_minimal_service.{server}:main", "target": "a",
                            "services": {"/add_two_ints": "example_interfaces/srv/AddTwoInts"}},
        "minimal_client": {"run": f"examples_rclpy_minimal_client.{client}:main", "target": "b", "required": True,
                           "clients": {"/add_two_ints": "example_interfaces/srv/AddTwoInts"}},
    }, [services / "minimal_service", services / "minimal_client"], 30)
    assert done.returncode == 0, done.stderr
    assert "[minimal_service]: Incoming request\na: 41 b: 1\n" in done.stderr
    assert f"[{client_name}]: Result of add_two_ints: for 41 + 1 = 42\n" in done.stderr
    assert "Traceback" not in done.stderr


ACTION = "example_interfaces/action/Fibonacci"
FIBONACCI = "array('i', [0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55])"


def test_the_minimal_action_servers_and_clients(tmp_path: Path) -> None:
    """Four server/client pairs at once, each pair in a namespace of its own (their code names the same
    action, 'fibonacci'): results, feedback, deferred execution and cancel, printed as ROS 2 prints them."""
    actions = RCLPY / "actions"
    pairs = {"plain": ("server", "client"), "deferred": ("server_defer", "client"),
             "functions": ("server_not_composable", "client_not_composable"), "cancel": ("server", "client_cancel")}
    nodes: dict[str, dict[str, object]] = {}
    for namespace, (server, client) in pairs.items():
        nodes[f"{namespace}_server"] = {"run": f"examples_rclpy_minimal_action_server.{server}:main", "target": "a",
                                        "namespace": namespace, "actions": {"fibonacci": ACTION}}
        nodes[f"{namespace}_client"] = {"run": f"examples_rclpy_minimal_action_client.{client}:main", "target": "b",
                                        "namespace": namespace, "action_clients": {"fibonacci": ACTION}}
    done = launch(tmp_path, nodes, [actions / "minimal_action_server", actions / "minimal_action_client"], 13.5)
    assert done.returncode == 0, done.stderr
    out = done.stderr
    for namespace in ("plain", "deferred", "functions"):
        assert f"[{namespace}.minimal_action_client]: Goal accepted :)" in out, out
        assert f"[{namespace}.minimal_action_client]: Goal succeeded! Result: {FIBONACCI}" in out, out
        assert f"[{namespace}.minimal_action_server]: Returning result: {FIBONACCI}" in out, out
    feedback = re.findall(r"\[plain\.minimal_action_client\]: Received feedback: (.*)", out)
    assert feedback == [f"array('i', {[0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55][:n]})" for n in range(3, 12)], out
    assert "[deferred.minimal_action_server]: Deferring execution..." in out
    assert "[cancel.minimal_action_server]: Received cancel request" in out
    assert "[cancel.minimal_action_client]: Goal successfully canceled" in out
    assert "[cancel.minimal_action_server]: Goal canceled" in out
    assert "Traceback" not in out


EXECUTORS = RCLPY / "executors"


def test_the_executors_examples(tmp_path: Path) -> None:
    """ros2/examples' executors package: talker and listener in two processes, and in one process each the
    composed nodes, a callback group, a custom (token-bucket) callback group and a custom executor."""
    chatter = {"chatter": "std_msgs/msg/String"}
    mains = "examples_rclpy_executors.{}:main".format
    (tmp_path / "estop.py").write_text(
        "from std_msgs.msg import String\n\n"
        "def estop(node):\n"
        "    publisher = node.create_publisher(String, 'estop')\n"
        "    node.create_timer(1.0, lambda: publisher.publish(String(data='STOP')))\n")
    done = launch(tmp_path, {
        "talker": {"run": mains("talker"), "target": "a", "namespace": "apart", "publish": chatter},
        "listener": {"run": mains("listener"), "target": "b", "namespace": "apart", "subscribe": chatter},
        "composed": {"run": mains("composed"), "target": "a", "namespace": "composed", "publish": chatter,
                     "subscribe": chatter},
        "callback_group": {"run": mains("callback_group"), "target": "b", "namespace": "grouped",
                           "publish": chatter, "subscribe": chatter},
        "custom_callback_group": {"run": mains("custom_callback_group"), "target": "a", "namespace": "throttled",
                                  "publish": chatter},
        "custom_executor": {"run": mains("custom_executor"), "target": "b", "namespace": "prioritised",
                            "publish": chatter, "subscribe": {**chatter, "estop": "std_msgs/msg/String"}},
        "estop": {"run": "estop:estop", "target": "a", "namespace": "prioritised",
                  "publish": {"estop": "std_msgs/msg/String"}},
    }, [EXECUTORS, tmp_path], 3.6, {"/throttled/chatter": {"history": "keep_last", "depth": 10}})
    assert done.returncode == 0, done.stderr
    out = done.stderr
    for namespace in ("apart", "composed", "prioritised"):
        assert f'[{namespace}.talker]: Publishing: "Hello World: 2"' in out, out
        assert f'[{namespace}.listener]: I heard: "Hello World: 2"' in out, out
    assert '[grouped.double_talker]: Publishing: "Hello World: 5"' in out  # two timers: 1 s and 0.5 s
    assert '[grouped.listener]: I heard: "Hello World: 5"' in out
    assert '[prioritised.estopper]: I heard: "STOP"' in out
    throttled = re.findall(r"\[throttled\.intermittent_talker\]: Publishing: \"Hello World: (\d+)\"", out)
    assert 13 <= len(throttled) <= 18, throttled  # a bucket of 10 at 10 Hz, then a token every 0.5 s
    assert "Traceback" not in out
