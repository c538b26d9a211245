"""Several subscriptions to one topic in one node each receive every message, as in ROS: with 2, 3 and
10 subscriptions in one graph (three listener nodes), on every transport a node's reader can sit on —
in-process delivery (threads), shared memory (processes), DDS (two hosts) and TCPROS (`kind: ros1`
targets, one listener sharing the talker's process) — on a reliable keep_all topic of depth 4, so
that back-pressure runs through every branch."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.netns import namespaces, unavailable
from tests.support.ros1 import needs_ros1, ros1_master

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

COUNTS = (2, 3, 10)


def _project(folder: Path, targets: str, talker_target: str, listener_targets: tuple[str, str, str],
             extra: str = "") -> Path:
    """The talker and a listener per entry of ``COUNTS`` (that many subscriptions each); the launch ends
    when all have returned."""
    (folder / "nodes.py").write_text(NODES)
    listeners = "".join(
        f"  listener{subs}: {{run: nodes:listener, target: {target},\n"
        f"     parameters: {{count: 300, subscriptions: {subs}}}, subscribe: {{/chatter: std_msgs/msg/UInt64}}}}\n"
        for subs, target in zip(COUNTS, listener_targets, strict=True))
    path = folder / "project.yaml"
    path.write_text(f"name: many_subs\n{extra}targets: {targets}\nnodes:\n"
                    f"  talker: {{run: nodes:talker, target: {talker_target}, parameters: {{count: 300}},\n"
                    "     publish: {/chatter: std_msgs/msg/UInt64}}\n" + listeners +
                    "topics:\n  /chatter: {reliability: reliable, history: keep_all, depth: 4}\n")
    return path


def _all_heard(output: str) -> None:
    for subs in COUNTS:
        assert f"{subs} subscriptions each heard all 300 messages in order" in output, output


@pytest.mark.parametrize("kind", ["thread", "process"])
def test_every_subscription_of_a_node_hears_every_message(tmp_path: Path, kind: str) -> None:
    project = _project(tmp_path, f"{{a: {{kind: {kind}}}, b: {{kind: {kind}}}, c: {{kind: {kind}}}}}", "a",
                       ("a", "b", "c"))
    command = [sys.executable, "-m", "hetros", "launch", str(project), "--duration", "60"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    _all_heard(done.stderr)


@pytest.mark.skipif(bool(unavailable()), reason=f"no network namespaces here: {unavailable()}")
def test_every_subscription_hears_every_message_over_dds(tmp_path: Path) -> None:
    """The talker on one host; on the other, one listener on a thread and two in processes."""
    with namespaces(2) as spaces:
        hosts = "".join(f"  h{i}: {{address: {s.address}}}\n" for i, s in enumerate(spaces))
        project = _project(tmp_path, "{t: {kind: process, host: h0}, l: {kind: thread, host: h1}, "
                           "p: {kind: process, host: h1}, q: {kind: process, host: h1}}", "t", ("l", "p", "q"),
                           f"hosts:\n{hosts}")
        launches = [subprocess.Popen(space.command(sys.executable, "-m", "hetros", "launch", str(project), "--as",
                                                   f"h{i}", "--duration", "60"),
                                     cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                    for i, space in enumerate(spaces)]
        outputs = [launched.communicate(timeout=120)[0] for launched in launches]
    assert [launched.returncode for launched in launches] == [0, 0], outputs
    _all_heard(outputs[1])


@needs_ros1
def test_every_subscription_hears_every_message_over_tcpros(tmp_path: Path) -> None:
    """ROS 1 nodes: one listener in the talker's process, two in another, all through a master."""
    for uri, _env in ros1_master():
        project = _project(tmp_path, "{r: {kind: ros1}, s: {kind: ros1}}", "r", ("r", "s", "s"),
                           f"external:\n  ros1: {{master: '{uri}'}}\n")
        done = subprocess.run([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "60"],
                              capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        _all_heard(done.stderr)
