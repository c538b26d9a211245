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
