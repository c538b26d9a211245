"""Several subscriptions to one topic in one node each receive every message, as in ROS: on threads
(in-process delivery) and on processes (shared memory), with 2, 3 and 10 subscriptions, a reliable
keep_all topic of depth 4 so that back-pressure runs through every branch."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

NODES = '''
from hetros import Node
from hetros.interfaces.std_msgs.msg import UInt64


def talker(node: Node) -> None:
    pub = node.create_publisher(UInt64, "/chatter")
    for i in range(node.get_parameter("count")):
        pub.publish(UInt64(data=i))


def listener(node: Node) -> None:
    """Callbacks on every subscription but the last, which the node's own loop takes from."""
    count, subs = node.get_parameter("count"), node.get_parameter("subscriptions")
    heard: list[list[int]] = [[] for _ in range(subs)]
    for k in range(subs - 1):
        node.create_subscription(UInt64, "/chatter", lambda m, k=k: heard[k].append(m.data))
    last = node.create_subscription(UInt64, "/chatter")
    while any(len(h) < count for h in heard):
        node.spin_once(0.05)
        while (message := last.try_take()) is not None:
            heard[-1].append(message.data)
    if not all(h == list(range(count)) for h in heard):
        raise ValueError(f"lengths {[len(h) for h in heard]}")
    node.log.info("%d subscriptions each heard all %d messages in order", subs, count)
'''


@pytest.mark.parametrize("subscriptions", [2, 3, 10])
@pytest.mark.parametrize("kind", ["thread", "process"])
def test_every_subscription_of_a_node_hears_every_message(tmp_path: Path, kind: str, subscriptions: int) -> None:
    (tmp_path / "nodes.py").write_text(NODES)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""\
        name: many_subs
        targets: {{a: {{kind: {kind}}}, b: {{kind: {kind}}}}}
        nodes:
          talker:   {{run: nodes:talker, target: a, parameters: {{count: 300}},
                     publish: {{/chatter: std_msgs/msg/UInt64}}}}
          listener: {{run: nodes:listener, target: b, required: true,
                     parameters: {{count: 300, subscriptions: {subscriptions}}},
                     subscribe: {{/chatter: std_msgs/msg/UInt64}}}}
        topics:
          /chatter: {{reliability: reliable, history: keep_all, depth: 4}}
        """))
    command = [sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration", "60"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert f"{subscriptions} subscriptions each heard all 300 messages in order" in done.stderr
