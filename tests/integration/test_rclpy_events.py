"""rclpy's subscription options with ROS's meaning: ``raw=True`` hands the serialized message (CDR with
its encapsulation header), ``event_callbacks`` runs deadline callbacks, and an event hetros never raises
is refused by name instead of being ignored."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

NODES = '''
import time

import rclpy
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.node import Node
from std_msgs.msg import String


class Listener(Node):
    def __init__(self) -> None:
        super().__init__("serialized_listener")
        self.create_subscription(String, "chatter", self.on_bytes, 10, raw=True)
        self.create_subscription(String, "chatter", lambda msg: None, 10,
                                 event_callbacks=SubscriptionEventCallbacks(deadline=self.on_deadline))

    def on_bytes(self, msg: bytes) -> None:
        self.get_logger().info(f"raw {type(msg).__name__} {msg!r}")

    def on_deadline(self, status) -> None:
        self.get_logger().info(f"deadline missed, {status.total_count} in all")


def main() -> None:
    rclpy.init()
    rclpy.spin(Listener())


def lost() -> None:
    rclpy.init()
    node = rclpy.create_node("lost")
    node.create_subscription(String, "chatter", lambda msg: None, 10,
                             event_callbacks=SubscriptionEventCallbacks(incompatible_type=print))


def talker() -> None:
    rclpy.init()
    node = rclpy.create_node("talker")
    pub = node.create_publisher(String, "chatter", 10)
    for i in range(3):
        pub.publish(String(data=f"Hello World: {i}"))
        time.sleep(0.1)
'''


def _launch(tmp_path: Path, listener: str) -> subprocess.CompletedProcess[str]:
    (tmp_path / "nodes.py").write_text(NODES)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""\
        name: events
        targets: {{a: {{kind: process}}, b: {{kind: process}}}}
        nodes:
          talker: {{run: nodes:talker, target: a, publish: {{/chatter: std_msgs/msg/String}}}}
          listener: {{run: "nodes:{listener}", target: b, subscribe: {{/chatter: std_msgs/msg/String}}}}
        topics:
          /chatter: {{deadline: 0.3}}
        """))
    command = [sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration", "2"]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)


def test_raw_subscriptions_get_bytes_and_deadline_callbacks_run(tmp_path: Path) -> None:
    done = _launch(tmp_path, "main")
    assert done.returncode == 0, done.stderr
    for i in range(3):
        assert f"raw bytes b'\\x00\\x01\\x00\\x00\\x0f\\x00\\x00\\x00Hello World: {i}\\x00'" in done.stderr, \
            done.stderr
    assert "[serialized_listener]: deadline missed, 1 in all" in done.stderr


def test_an_event_hetros_never_raises_is_refused_by_name(tmp_path: Path) -> None:
    done = _launch(tmp_path, "lost")
    assert done.returncode != 0
    assert "subscription to /chatter: event_callbacks incompatible_type are events hetros does not raise" in done.stderr
