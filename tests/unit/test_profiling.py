"""What a node counts while ``HETROS_PROFILE`` is set (what ``hetros advise`` profiles from): its
thread's CPU time per message beside the wall time, and which input each publish followed."""

from __future__ import annotations

import time

import pytest

from hetros import Node
from hetros.interfaces.std_msgs.msg import Int32
from hetros.runtime import Graph, _entities


@pytest.fixture
def profiling(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_entities, "PROFILING", True)


def test_a_callback_counts_cpu_apart_from_sleeping_and_its_publishes_follow_its_input(profiling: None) -> None:
    graph = Graph.standalone()
    try:
        relay = Node("relay", graph)
        out = relay.create_publisher(Int32, "/b")

        def handle(message: Int32) -> None:
            deadline = time.thread_time() + 0.004
            while time.thread_time() < deadline:  # 4 ms of work
                pass
            time.sleep(0.02)  # and 20 ms of waiting, which is not work
            out.publish(Int32(data=message.data))

        subscription = relay.create_subscription(Int32, "/a", handle)
        source = Node("source", graph)
        pub = source.create_publisher(Int32, "/a")
        for tick in source.rate(200.0):
            pub.publish(Int32(data=tick))
            if tick == 4:
                break
        while relay.spin_once(0.2):
            pass
        snapshot = subscription.stats.snapshot()
        assert snapshot["count"] == 5 and snapshot["cpu_count"] == 5
        assert snapshot["cpu_total_s"] == pytest.approx(0.02, abs=0.01)  # 5 x 4 ms
        assert snapshot["total_s"] >= 5 * 0.02  # wall: the sleeps too
        assert len(snapshot["cpu_quantiles_s"]) == len(snapshot["quantiles_s"]) == 22
        assert relay.triggers == {("/a", "/b"): 5}
        assert source.triggers == {("", "/a"): 5}  # a rate loop's publishes are the period's
    finally:
        graph.close()


def test_a_take_loop_publish_follows_the_message_taken_until_a_rate_period_begins(profiling: None) -> None:
    graph = Graph.standalone()
    try:
        node = Node("loop", graph)
        inputs = node.create_subscription(Int32, "/in")
        out = node.create_publisher(Int32, "/out")
        feeder = Node("feeder", graph).create_publisher(Int32, "/in")
        feeder.publish(Int32(data=1))
        inputs.take(timeout=1.0)
        out.publish(Int32(data=1))  # while working on /in's message
        for _ in node.rate(100.0):
            out.publish(Int32(data=2))  # the period's doing, though /in was taken last
            break
        assert node.triggers == {("/in", "/out"): 1, ("", "/out"): 1}
    finally:
        graph.close()


def test_not_profiling_counts_no_cpu_and_no_triggers() -> None:
    graph = Graph.standalone()
    try:
        relay = Node("relay", graph)
        out = relay.create_publisher(Int32, "/b")
        subscription = relay.create_subscription(Int32, "/a", lambda m: out.publish(m))
        Node("source", graph).create_publisher(Int32, "/a").publish(Int32(data=1))
        while relay.spin_once(0.2):
            pass
        assert subscription.stats.count == 1 and "cpu_count" not in subscription.stats.snapshot()
        assert relay.triggers == {}
    finally:
        graph.close()
