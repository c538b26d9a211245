"""Deadline, lifespan and liveliness on every transport: in one process (inproc), between two
processes' graphs (shm, both in this test process), and over DDS edges between hosts."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import pytest

from hetros import (
    DeadlineMissedStatus,
    IncompatibleQosStatus,
    LivelinessChangedStatus,
    LivelinessLostStatus,
    MatchedStatus,
    MessageLostStatus,
    Node,
)
from hetros.interfaces.std_msgs.msg import Int32
from hetros.msg import registry
from hetros.plan import ChannelPlan, EdgePlan, NodePlan, Plan, TargetPlan
from hetros.runtime import Graph
from hetros.transport import MessageCodec, QoS, remove_session_segments
from hetros.transport.dds import DdsDomain, DdsEdgeReader, DdsEdgeWriter
from tests.support.ros2 import free_domain


def _graphs(session: str, qos: QoS, mapping: str) -> tuple[Graph, Graph]:
    targets = {"p1": TargetPlan("p1", "process"), "p2": TargetPlan("p2", "process")}
    where = ("p1", "p1") if mapping == "inproc" else ("p1", "p2")
    plan = Plan(
        "q", "/", (), targets,
        {"pub": NodePlan("pub", "m:f", where[0], publish={"/q": "std_msgs/msg/Int32"}),
         "sub": NodePlan("sub", "m:f", where[1], subscribe={"/q": "std_msgs/msg/Int32"})},
        {"/q": ChannelPlan("/q", "std_msgs/msg/Int32", "topic", qos, ("pub",), ("sub",))},
        (EdgePlan("/q", "pub", "sub", mapping),),
    )
    first = Graph(plan, "p1", session)
    return (first, first) if mapping == "inproc" else (first, Graph(plan, "p2", session))


@pytest.fixture(params=["inproc", "shm"])
def mapping(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def _spin_for(node: Node, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        node.spin_once(timeout=0.01)


def _spin_until(node: Node, condition: Callable[[], bool], patience: float = 20.0) -> None:
    """Spin until ``condition()`` holds: what must happen eventually, however slow the machine is."""
    end = time.monotonic() + patience
    while not condition() and time.monotonic() < end:
        node.spin_once(timeout=0.01)


@contextmanager
def _open(session: str, qos: QoS, mapping: str) -> Iterator[tuple[Node, Node]]:
    publishing, subscribing = _graphs(session, qos, mapping)
    try:
        yield Node("pub", publishing), Node("sub", subscribing)
    finally:
        subscribing.close()
        if publishing is not subscribing:
            publishing.close()
        remove_session_segments(session)


def test_a_missed_deadline_reaches_both_ends_on_every_mapping(shm_session: str, mapping: str) -> None:
    with _open(shm_session, QoS(deadline=0.25), mapping) as (pub_node, sub_node):
        sub_misses: list[DeadlineMissedStatus] = []
        pub_misses: list[DeadlineMissedStatus] = []
        got: list[int] = []
        sub_node.create_subscription(Int32, "/q", lambda m: got.append(m.data),
                                     on_deadline_missed=lambda s: sub_misses.append(DeadlineMissedStatus(**vars(s))))
        pub = pub_node.create_publisher(Int32, "/q",
                                        on_deadline_missed=lambda s: pub_misses.append(DeadlineMissedStatus(**vars(s))))
        for n in range(10):  # on time: no miss
            pub.publish(Int32(data=n))
            _spin_for(sub_node, 0.02)
            if pub_node is not sub_node:
                pub_node.spin_once(timeout=0)
        assert got == list(range(10)) and not sub_misses and not pub_misses
        _spin_for(sub_node, 1.3)  # silence: about five periods
        if pub_node is not sub_node:
            _spin_for(pub_node, 0.05)
        assert sub_misses and 3 <= sub_misses[-1].total_count <= 7, sub_misses
        assert pub_misses and pub_misses[-1].total_count >= 3, pub_misses


def test_a_message_older_than_its_lifespan_is_not_delivered(shm_session: str, mapping: str) -> None:
    with _open(shm_session, QoS(lifespan=0.5, depth=8), mapping) as (pub_node, sub_node):
        sub = sub_node.create_subscription(Int32, "/q")
        pub = pub_node.create_publisher(Int32, "/q")
        pub.publish(Int32(data=1))
        time.sleep(0.8)
        pub.publish(Int32(data=2))
        assert sub.take(timeout=2).data == 2, "the expired message was delivered"
        assert sub.try_take() is None


def test_liveliness_manual_by_topic_is_lost_past_the_lease_and_regained(shm_session: str, mapping: str) -> None:
    qos = QoS(liveliness="manual_by_topic", lease_duration=0.5)
    with _open(shm_session, qos, mapping) as (pub_node, sub_node):
        changes: list[tuple[int, int]] = []
        sub_node.create_subscription(Int32, "/q", lambda m: None, on_liveliness_changed=lambda s: changes.append(
            (s.alive_count, s.not_alive_count)))
        pub = pub_node.create_publisher(Int32, "/q")
        pub.publish(Int32(data=1))
        _spin_for(sub_node, 0.3)
        assert changes[-1] == (1, 0), changes
        _spin_for(sub_node, 1.2)  # no assertion for more than the lease
        assert changes[-1] == (0, 1), changes
        pub.assert_liveliness()
        _spin_for(sub_node, 0.3)
        assert changes[-1] == (1, 0), changes
        assert isinstance(LivelinessChangedStatus(), LivelinessChangedStatus)


def test_a_manual_publisher_hears_each_lease_it_let_pass(shm_session: str, mapping: str) -> None:
    """ROS 2's liveliness_lost: each silence past the lease is counted once; publishing renews the lease."""
    qos = QoS(liveliness="manual_by_topic", lease_duration=0.2)
    with _open(shm_session, qos, mapping) as (pub_node, _):
        lost: list[LivelinessLostStatus] = []
        pub = pub_node.create_publisher(Int32, "/q", on_liveliness_lost=lost.append)
        _spin_for(pub_node, 0.5)
        assert lost == [LivelinessLostStatus(1, 1)]
        pub.publish(Int32(data=1))
        _spin_for(pub_node, 0.1)
        assert len(lost) == 1
        _spin_for(pub_node, 0.4)
        assert lost[-1] == LivelinessLostStatus(2, 1)


def test_a_closed_publisher_of_the_process_is_gone_not_dead() -> None:
    """As ROS 2 counts a deleted writer: alive goes down by one, not_alive stays."""
    node = Node("both")
    changes: list[tuple[int, int, int, int]] = []
    node.create_subscription(Int32, "/g", lambda m: None, on_liveliness_changed=lambda s: changes.append(
        (s.alive_count, s.not_alive_count, s.alive_count_change, s.not_alive_count_change)))
    pub = node.create_publisher(Int32, "/g")
    _spin_until(node, lambda: bool(changes))
    assert changes == [(1, 0, 1, 0)]
    pub.close()
    _spin_until(node, lambda: len(changes) >= 2)
    assert changes == [(1, 0, 1, 0), (0, 0, -1, 0)]
    node.graph.close()


def test_over_dds_lifespan_is_enforced_and_liveliness_is_cyclones() -> None:
    domain = DdsDomain(free_domain())
    codec = MessageCodec(registry(), "std_msgs/msg/Int32")
    qos = QoS(depth=8, lifespan=0.5, liveliness="manual_by_topic", lease_duration=0.3)
    reader = DdsEdgeReader(domain, ["hetros/q/a/q"], codec, qos, lambda: None)
    writer = DdsEdgeWriter(domain, "hetros/q/a/q", codec, qos)
    try:
        deadline = time.monotonic() + 5
        while writer.matched() == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        writer.write(Int32(data=1))
        time.sleep(0.05)
        assert reader.liveliness() == (1, 0)
        time.sleep(0.8)  # older than the lifespan, silent past the lease
        writer.write(Int32(data=2))
        time.sleep(0.05)
        taken = []
        while (message := reader.try_take()) is not None:
            taken.append(message.data)
        assert taken == [2], taken
        time.sleep(0.5)
        assert reader.liveliness() == (0, 1)
        writer.write(Int32(data=3))  # a publish asserts liveliness (a bare assertion: see the README, QoS)
        time.sleep(0.1)
        assert reader.liveliness() == (1, 0)
    finally:
        reader.close()
        domain.close()


def test_a_malformed_sample_on_a_hosts_edge_is_dropped_counted_and_logged(caplog: pytest.LogCaptureFixture) -> None:
    """Another participant writes bytes that are not hetros's framing on an edge topic: the
    subscribing node used to get a SerializationError (and die); the sample is dropped."""
    from cyclonedds.pub import DataWriter

    from hetros.transport.dds._domain import dds_qos
    from hetros.transport.dds._edges import _SAMPLE

    domain = DdsDomain(free_domain())
    codec = MessageCodec(registry(), "std_msgs/msg/Int32")
    qos = QoS(depth=8)
    reader = DdsEdgeReader(domain, ["hetros/m/a/q"], codec, qos, lambda: None)
    writer = DdsEdgeWriter(domain, "hetros/m/a/q", codec, qos)
    rogue = DataWriter(domain.participant, domain.topic("hetros/m/a/q", _SAMPLE), qos=dds_qos(qos))
    try:
        deadline = time.monotonic() + 5
        while (writer.matched() == 0 or len(rogue.get_matched_subscriptions()) == 0) and time.monotonic() < deadline:
            time.sleep(0.01)
        for junk in (b"", b"\x00\x01\x00\x00", b"\x00\x01\x00\x00\x01\x02"):  # no body, short bodies
            rogue.write(_SAMPLE(data=list(junk)))
        writer.write(Int32(data=7))
        time.sleep(0.2)
        reader._arrived()
        assert reader.try_take().data == 7
        assert reader.dropped == 3
        assert "dropped a malformed sample from another host" in caplog.text
    finally:
        reader.close()
        domain.close()


def test_messages_a_keep_last_subscription_lost_are_reported(shm_session: str, mapping: str) -> None:
    """rclpy's message_lost event: what keep_last overwrote before the subscription took it."""
    with _open(shm_session, QoS(history="keep_last", depth=2), mapping) as (pub_node, sub_node):
        reports: list[tuple[int, int]] = []

        def lost(status: MessageLostStatus) -> None:
            reports.append((status.total_count, status.total_count_change))
        heard: list[int] = []
        sub_node.create_subscription(Int32, "/q", lambda m: heard.append(m.data), on_message_lost=lost)
        pub = pub_node.create_publisher(Int32, "/q")
        for i in range(10):
            pub.publish(Int32(data=i))
        _spin_until(sub_node, lambda: len(heard) >= 2 and sum(change for _, change in reports) >= 8)
        assert heard == [8, 9]
        assert reports and reports[-1][0] == 8 and sum(change for _, change in reports) == 8, reports


def test_matched_events_count_other_processes_from_the_start_and_this_ones_as_they_come(
        shm_session: str, mapping: str) -> None:
    """ROS 2's matched events: a publisher and a subscription each hear of the other once both exist (the
    plan's endpoint in another process counts from the start), and of an endpoint of this process that
    goes away; a second local subscription adds one to the count, as in ROS 2."""
    with _open(shm_session, QoS(), mapping) as (pub_node, sub_node):
        to_pub: list[MatchedStatus] = []
        to_sub: list[MatchedStatus] = []
        pub = pub_node.create_publisher(Int32, "/q", on_matched=to_pub.append)
        sub = sub_node.create_subscription(Int32, "/q", lambda m: None, on_matched=to_sub.append)
        _spin_until(pub_node, lambda: bool(to_pub))
        _spin_until(sub_node, lambda: bool(to_sub))
        assert to_pub == [MatchedStatus(1, 1, 1, 1)]
        assert to_sub == [MatchedStatus(1, 1, 1, 1)]
        if mapping == "inproc":
            second = sub_node.create_subscription(Int32, "/q", lambda m: None)
            _spin_until(pub_node, lambda: len(to_pub) >= 2)
            assert to_pub[-1] == MatchedStatus(2, 1, 2, 1)
            second.close()
            sub.close()
            _spin_until(pub_node, lambda: len(to_pub) >= 3)
            assert to_pub[-1] == MatchedStatus(2, 0, 0, -2)
        else:
            sub.close()  # the other process' subscription: planned, so still matched
            _spin_for(pub_node, 0.05)
            assert len(to_pub) == 1
        pub.close()


def test_endpoints_whose_own_qos_does_not_match_are_told_and_not_delivered_to() -> None:
    """Without a project QoS, each endpoint's own QoS decides matching, as in ROS 2: a best_effort offer to a
    reliable request is incompatible on both sides, and the subscription hears nothing until a publisher
    that serves it appears."""
    node = Node("both")
    told: list[tuple[str, IncompatibleQosStatus]] = []
    heard: list[int] = []
    weak = node.create_publisher(Int32, "/i", qos=QoS(reliability="best_effort"),
                                 on_incompatible_qos=lambda s: told.append(("pub", s)))
    node.create_subscription(Int32, "/i", lambda m: heard.append(m.data), qos=QoS(),
                             on_incompatible_qos=lambda s: told.append(("sub", s)))
    weak.publish(Int32(data=1))
    _spin_for(node, 0.1)
    assert sorted(who for who, _ in told) == ["pub", "sub"]
    assert all(status == IncompatibleQosStatus(1, 1, "reliability") for _, status in told)
    assert heard == []
    strong = node.create_publisher(Int32, "/i", qos=QoS())
    strong.publish(Int32(data=2))
    _spin_for(node, 0.1)
    assert heard == [2]
    node.graph.close()


def test_a_project_qos_makes_every_endpoint_match() -> None:
    plan = Plan("q", "/", (), {"p1": TargetPlan("p1", "process")},
                {"pub": NodePlan("pub", "m:f", "p1", publish={"/q": "std_msgs/msg/Int32"}),
                 "sub": NodePlan("sub", "m:f", "p1", subscribe={"/q": "std_msgs/msg/Int32"})},
                {"/q": ChannelPlan("/q", "std_msgs/msg/Int32", "topic", QoS(), ("pub",), ("sub",))},
                (EdgePlan("/q", "pub", "sub", "inproc"),))
    graph = Graph(plan, "p1", "")
    told: list[IncompatibleQosStatus] = []
    Node("pub", graph).create_publisher(Int32, "/q", qos=QoS(reliability="best_effort"),
                                        on_incompatible_qos=told.append)
    sub_node = Node("sub", graph)
    matched: list[MatchedStatus] = []
    sub_node.create_subscription(Int32, "/q", lambda m: None, qos=QoS(), on_incompatible_qos=told.append,
                                 on_matched=matched.append)
    _spin_for(sub_node, 0.05)
    assert told == [] and matched == [MatchedStatus(1, 1, 1, 1)]
    graph.close()
