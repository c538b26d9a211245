from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest

from hetros import (
    Node,
    ParameterError,
    PublishTimeoutError,
    QoS,
    ReadOnlyMessageError,
    ServiceTimeoutError,
    TakeTimeoutError,
    TopicTypeError,
    UndeclaredEndpointError,
)
from hetros.interfaces.example_interfaces.srv import AddTwoInts
from hetros.interfaces.std_msgs.msg import Int32, String
from hetros.runtime import Graph


@pytest.fixture
def graph() -> Iterator[Graph]:
    g = Graph.standalone()
    yield g
    g.close()


def spin_in_thread(node: Node) -> threading.Thread:
    thread = threading.Thread(target=node.spin, daemon=True)
    thread.start()
    return thread


def test_callbacks_of_one_node_never_run_concurrently(graph: Graph) -> None:
    node = Node("worker", graph)
    active = 0
    overlaps = 0
    calls = 0
    lock = threading.Lock()

    def callback(_msg: object) -> None:
        nonlocal active, overlaps, calls
        with lock:
            active += 1
            overlaps += active > 1
        time.sleep(0.001)
        with lock:
            active -= 1
            calls += 1

    for topic in ("/a", "/b", "/c"):
        node.create_subscription(String, topic, callback, qos=QoS(depth=100))
    node.create_timer(0.001, lambda: callback(None))
    thread = spin_in_thread(node)
    pubs = [Node(f"p{i}", graph).create_publisher(String, t, qos=QoS(depth=100))
            for i, t in enumerate(("/a", "/b", "/c"))]
    senders = [threading.Thread(target=lambda p=p: [p.publish(String(data="x")) for _ in range(50)])
               for p in pubs]
    for s in senders:
        s.start()
    for s in senders:
        s.join()
    deadline = time.monotonic() + 5
    while calls < 150 and time.monotonic() < deadline:
        time.sleep(0.01)
    graph.shutdown()
    thread.join(2)
    assert calls >= 150
    assert overlaps == 0


def test_take_try_take_and_iterator(graph: Graph) -> None:
    sub = Node("s", graph).create_subscription(Int32, "/n")
    pub = Node("p", graph).create_publisher(Int32, "/n")
    assert sub.try_take() is None
    with pytest.raises(TakeTimeoutError, match="/n"):
        sub.take(timeout=0.05)
    pub.publish(Int32(data=1))
    assert sub.take(timeout=1).data == 1
    pub.publish(Int32(data=2))
    threading.Timer(0.2, graph.shutdown).start()
    assert [m.data for m in sub] == [2]


def test_take_loop_node_time_runs_from_a_take_returning_to_the_next_take(graph: Graph) -> None:
    """A take that times out ends the interval it was called in and starts none: the wait
    for the next message is not the node's work."""
    sub = Node("s", graph).create_subscription(Int32, "/n")
    pub = Node("p", graph).create_publisher(Int32, "/n")
    pub.publish(Int32(data=1))
    sub.take(timeout=1)
    assert sub.stats.summary()[0] == 0
    with pytest.raises(TakeTimeoutError):
        sub.take(timeout=0.05)
    assert sub.stats.summary()[0] == 1
    pub.publish(Int32(data=2))
    sub.take(timeout=1)
    assert sub.stats.summary()[0] == 1, "the timed-out wait was counted as node time"
    pub.publish(Int32(data=3))
    sub.take(timeout=1)
    assert sub.stats.summary()[0] == 2


def test_a_take_loop_over_two_topics_does_not_count_the_wait_for_the_other(graph: Graph,
                                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """lane_control's shape: take /a, then wait for /b. The time on /a's message ends when the
    node takes again, on either topic; the wait for /b is not spent on /a's message."""
    clock = [100.0]
    monkeypatch.setattr("hetros.runtime._entities.time.perf_counter", lambda: clock[0])
    node = Node("s", graph)
    a, b = node.create_subscription(Int32, "/a"), node.create_subscription(Int32, "/b")
    pub_a, pub_b = Node("p", graph).create_publisher(Int32, "/a"), Node("q", graph).create_publisher(Int32, "/b")
    pub_a.publish(Int32(data=1))
    a.take(timeout=1)
    clock[0] += 0.002  # 2 ms of work on /a's message
    pub_b.publish(Int32(data=2))
    b.take(timeout=1)
    clock[0] += 0.500  # then the node is idle, or waits elsewhere, half a second
    pub_a.publish(Int32(data=3))
    a.take(timeout=1)
    assert a.stats.count == 1 and abs(a.stats.summary()[1] - 2.0) < 1e-6  # ms
    assert b.stats.count == 1 and abs(b.stats.summary()[1] - 500.0) < 1e-6


def test_published_message_is_handed_over_read_only(graph: Graph) -> None:
    sub = Node("s", graph).create_subscription(String, "/x")
    pub = Node("p", graph).create_publisher(String, "/x")
    msg = String(data="a")
    pub.publish(msg)
    got = sub.try_take()
    assert got is msg, "inproc hands over the object itself"
    with pytest.raises(ReadOnlyMessageError):
        msg.data = "b"
    assert got.copy().data == "a"


def test_a_kept_message_stays_the_callers_and_is_copied_only_for_readers_in_process(graph: Graph) -> None:
    """``publish(keep=True)``, rclpy's and rospy's rule: in process the subscriber gets a copy and the
    message stays writable; a writer that serializes (every transport between processes) is given the
    message itself, unsealed, and nothing is copied."""
    from hetros.msg import registry
    from hetros.runtime._endpoints import endpoint_writer
    from hetros.transport import Writer

    sub = Node("s", graph).create_subscription(String, "/x")
    pub = Node("p", graph).create_publisher(String, "/x")
    msg = String(data="a")
    pub.publish(msg, keep=True)
    msg.data = "b"
    got = sub.try_take()
    assert got is not msg and got.data == "a" and got.is_frozen

    class Serializing(Writer):
        """A transport between processes, as the runtime sees one: it encodes what it is given at once."""

        def __init__(self) -> None:
            self.written: list[tuple[object, str]] = []

        def write(self, message: String) -> None:
            self.written.append((message, message.data))

        def close(self) -> None:
            pass

    serializing = Serializing()
    pub._writer = endpoint_writer([serializing], registry())
    pub.publish(msg, keep=True)
    msg.data = "c"
    assert serializing.written == [(msg, "b")] and not msg.is_frozen


def test_wrong_type_is_refused_with_the_topic_named(graph: Graph) -> None:
    pub = Node("p", graph).create_publisher(String, "/x")
    with pytest.raises(TopicTypeError, match="topic /x carries std_msgs/msg/String, not std_msgs/msg/Int32"):
        pub.publish(Int32(data=1))  # type: ignore[arg-type]


def test_backpressure_timeout_through_the_node_api(graph: Graph) -> None:
    Node("s", graph).create_subscription(Int32, "/q", qos=QoS(depth=1, publish_timeout=0.1))
    pub = Node("p", graph).create_publisher(Int32, "/q")
    pub.publish(Int32(data=1))
    with pytest.raises(PublishTimeoutError, match="raise 'depth'"):
        pub.publish(Int32(data=2))


def test_service_call_inside_a_callback_does_not_deadlock(graph: Graph) -> None:
    server = Node("server", graph)
    server.create_service(AddTwoInts, "/add", lambda rq: AddTwoInts.Response(sum=rq.a + rq.b))
    node = Node("dip", graph)
    client = node.create_client(AddTwoInts, "/add")
    results: list[int] = []
    node.create_subscription(Int32, "/in", lambda m: results.append(
        client.call(AddTwoInts.Request(a=m.data, b=1), timeout=2).sum))
    threads = [spin_in_thread(server), spin_in_thread(node)]
    pub = Node("p", graph).create_publisher(Int32, "/in")
    for i in range(3):
        pub.publish(Int32(data=i))
    deadline = time.monotonic() + 5
    while len(results) < 3 and time.monotonic() < deadline:
        time.sleep(0.01)
    future = client.call_async(AddTwoInts.Request(a=20, b=22))
    assert future.result(2).sum == 42
    graph.shutdown()
    for t in threads:
        t.join(2)
    assert results == [1, 2, 3]


def test_service_timeout_names_the_service(graph: Graph) -> None:
    Node("server", graph).create_service(AddTwoInts, "/slow", lambda rq: AddTwoInts.Response())
    client = Node("c", graph).create_client(AddTwoInts, "/slow")  # the server never spins
    with pytest.raises(ServiceTimeoutError, match=r"/slow did not reply within 0\.1 s"):
        client.call(AddTwoInts.Request(), timeout=0.1)


def test_timer_and_rate_end_on_shutdown(graph: Graph) -> None:
    node = Node("t", graph)
    ticks: list[float] = []
    node.create_timer(0.01, lambda: ticks.append(time.monotonic()))
    threading.Timer(0.3, graph.shutdown).start()
    node.spin()
    assert len(ticks) >= 5
    assert list(node.rate(100.0)) == []


def test_parameters(graph: Graph) -> None:
    node = Node("n", graph, parameters={"gain": 2.5})
    assert node.get_parameter("gain") == 2.5
    assert node.get_parameter("other", 1) == 1
    with pytest.raises(ParameterError, match=r"nodes\.n\.parameters\.missing"):
        node.get_parameter("missing")


def test_log_lines_carry_the_node_name(graph: Graph, caplog: pytest.LogCaptureFixture) -> None:
    from hetros.runtime._log import NodeFormatter

    node = Node("talker", graph)
    with caplog.at_level("INFO", logger="hetros"):
        node.log.info("hello %d", 1)
    assert NodeFormatter().format(caplog.records[-1]) == "[INFO] [talker]: hello 1"


def test_undeclared_endpoint_refused_at_run_time() -> None:
    from hetros.plan import ChannelPlan, NodePlan, Plan, TargetPlan

    plan = Plan("p", "/", (), {"main": TargetPlan("main", "thread")},
                {"a": NodePlan("a", "m:f", "main", publish={"/x": "std_msgs/msg/String"})},
                {"/x": ChannelPlan("/x", "std_msgs/msg/String", "topic", QoS(), ("a",), ())}, ())
    graph = Graph(plan)
    node = Node("a", graph)
    node.create_publisher(String, "/x")
    with pytest.raises(UndeclaredEndpointError, match=r"nodes\.a\.publish"):
        node.create_publisher(String, "/y")
    with pytest.raises(TopicTypeError, match="project declares std_msgs/msg/String"):
        node.create_publisher(Int32, "/x")
    graph.close()


def test_publishing_one_reused_buffer_in_a_loop_works(graph: Graph) -> None:
    """publish never takes the caller's arrays: a refilled buffer is copied for in-process readers."""
    from hetros.interfaces.std_msgs.msg import UInt8MultiArray

    node = Node("camera", graph)
    sub = node.create_subscription(UInt8MultiArray, "/frames", qos=QoS(depth=10))
    pub = node.create_publisher(UInt8MultiArray, "/frames", qos=QoS(depth=10))
    buffer = np.zeros(4, np.uint8)
    for value in range(3):
        buffer[:] = value                       # the common pattern: fill one buffer, publish it
        pub.publish(UInt8MultiArray(data=buffer))
    got = [sub.take(timeout=1.0) for _ in range(3)]
    assert [int(m.data[0]) for m in got] == [0, 1, 2]
    assert buffer.flags.writeable
    assert not got[0].data.flags.writeable


def test_a_loaned_message_travels_without_a_copy_in_process(graph: Graph) -> None:
    from hetros.interfaces.std_msgs.msg import UInt8MultiArray

    node = Node("camera", graph)
    sub = node.create_subscription(UInt8MultiArray, "/frames")
    pub = node.create_publisher(UInt8MultiArray, "/frames")
    message = pub.loan(data=1000)
    message.data[:] = 7
    filled = message.data
    pub.publish(message)
    got = sub.take(timeout=1.0)
    assert np.shares_memory(got.data, filled), "zero copies for a loan"
    assert not got.data.flags.writeable
    with pytest.raises(ReadOnlyMessageError):
        message.data = np.zeros(3, np.uint8)


def test_the_read_only_promise_covers_lists_and_views_of_the_callers_memory(graph: Graph) -> None:
    """What a subscriber holds cannot change under it: not through a list, not through a view."""
    from hetros.interfaces.diagnostic_msgs.msg import DiagnosticStatus, KeyValue
    from hetros.interfaces.std_msgs.msg import UInt8MultiArray

    node = Node("n", graph)
    statuses = node.create_subscription(DiagnosticStatus, "/status")
    node.create_publisher(DiagnosticStatus, "/status").publish(
        DiagnosticStatus(name="arm", values=[KeyValue(key="t", value="20")]))
    got = statuses.take(timeout=1.0)
    assert got.values == [KeyValue(key="t", value="20")]
    with pytest.raises(ReadOnlyMessageError):
        got.values.append(KeyValue(key="x", value="y"))
    with pytest.raises(ReadOnlyMessageError):
        got.values[0] = KeyValue()
    assert got.copy().values.append(KeyValue()) is None, "a copy is writable again"

    frames = node.create_subscription(UInt8MultiArray, "/frames")
    buffer = np.zeros(4, np.uint8)
    view = buffer.view()
    view.flags.writeable = False  # read-only, but the caller can still write through `buffer`
    node.create_publisher(UInt8MultiArray, "/frames").publish(UInt8MultiArray(data=view))
    buffer[:] = 5
    assert frames.take(timeout=1.0).data.tolist() == [0, 0, 0, 0]


def test_stop_hooks_run_once_however_often_the_graph_stops() -> None:
    """rospy.on_shutdown hooks ran twice (a stop request, then the process' close)."""
    graph = Graph.standalone()
    calls: list[str] = []
    graph.on_stop(lambda: calls.append("before"))
    graph.shutdown()
    graph.shutdown()
    graph.on_stop(lambda: calls.append("after"))  # registered once stopped: runs at once, once
    graph.close()
    assert calls == ["before", "after"]
