"""hetros.compat's message flavour and ROS 1 field errors, without a running graph."""

from __future__ import annotations

import array
import os
import threading
import time

import numpy as np
import pytest

from hetros import ReadOnlyMessageError
from hetros.compat._flavour import SequenceView, flavoured, flavoured_action, received
from hetros.compat.rclpy.task import Future, run_to_end
from hetros.msg import copy, freeze, registry


def test_a_constructed_numeric_sequence_is_an_array_array_as_in_rclpy() -> None:
    feedback = flavoured(registry().get("example_interfaces/action/Fibonacci_Feedback"))()
    assert isinstance(feedback.sequence, array.array) and feedback.sequence.typecode == "i"
    feedback.sequence = [0, 1]
    feedback.sequence.append(1)
    assert f"{feedback.sequence}" == "array('i', [0, 1, 1])"
    copied = copy(feedback)  # what the shims hand to the transports: hetros's own class, numpy arrays
    assert type(copied) is registry().get("example_interfaces/action/Fibonacci_Feedback")
    assert np.array_equal(copied.sequence, [0, 1, 1])


def _same(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return type(a) is type(b) and np.array_equal(a, b)  # type: ignore[arg-type]
    if getattr(a, "__msgtype__", None):
        return type(a) is type(b) and all(_same(getattr(a, f), getattr(b, f)) for f in a.__fieldnames__)
    return type(a) is type(b) and a == b


def test_the_flavoured_constructor_stores_what_assigning_each_field_stores() -> None:
    """Flavoured classes have a generated constructor of their own (the base's one stored sequences through
    the properties, 0.45 µs per new Image): for every shipped type with numeric sequences it must give what
    the base's constructor and the properties give, for defaults, None, lists, arrays and empty arrays."""
    from hetros.compat._flavour import _sequences

    checked = 0
    for typename in sorted(registry().fielddefs):
        base = registry().get(typename)
        sequences = _sequences(typename)
        if not sequences or "/msg/" not in typename:
            continue
        cls = flavoured(base)
        assert cls.__init__ is not base.__init__
        plain, made = base(), cls()
        for name in base.__fieldnames__:
            value = getattr(made, name)
            if name in sequences:
                assert type(value) is array.array and value.typecode == sequences[name] and not value, typename
            else:
                assert _same(value, getattr(plain, name)), f"{typename}.{name}"
        for name, code in sequences.items():
            dtype = np.dtype(code)
            for given in ([1, 2], np.arange(3, dtype=dtype), np.zeros(0, dtype=dtype), None):
                reference = cls()
                setattr(reference, name, base(**{name: given}).__getattribute__(name) if given is not None else
                        np.zeros(0, dtype=dtype))
                assert _same(cls(**{name: given}).__getattribute__(name), getattr(reference, name)), \
                    f"{typename}.{name} = {given!r}"
        checked += 1
    assert checked > 20


def test_served_types_print_as_rclpy_prints_them_and_copy_into_hetros_classes() -> None:
    """rosidl's repr: the module path, numeric sequences as lists ([] when empty), messages inside alike; a
    copy (what publish sends) is of hetros's own class again."""
    string = registry().get("std_msgs/msg/String")
    served = flavoured(string)
    assert issubclass(served, string) and served.__slots__ == ()
    assert repr(served(data="hi")) == "std_msgs.msg.String(data='hi')"
    assert type(copy(served(data="hi"))) is string
    fibonacci = flavoured_action(registry().get_action("example_interfaces/action/Fibonacci"))
    assert fibonacci.Result().sequence.typecode == "i"
    assert str(fibonacci.Result(sequence=[0, 1, 1])) == "example_interfaces.action.Fibonacci_Result(sequence=[0, 1, 1])"
    assert str(fibonacci.Result()) == "example_interfaces.action.Fibonacci_Result(sequence=[])"
    image = flavoured(registry().get("sensor_msgs/msg/Image"))()
    assert repr(image).startswith("sensor_msgs.msg.Image(header=std_msgs.msg.Header(stamp=builtin_interfaces.msg."
                                  "Time(sec=0, nanosec=0), frame_id=''), height=0,")


def test_a_received_read_only_message_prints_as_rclpy_and_stays_read_only() -> None:
    result_type = registry().get("example_interfaces/action/Fibonacci_Result")
    message = freeze(result_type(sequence=np.array([0, 1, 1], dtype=np.int32)))
    received(message)
    assert str(message) == "example_interfaces.action.Fibonacci_Result(sequence=[0, 1, 1])"
    assert message.is_frozen
    with pytest.raises(ReadOnlyMessageError):
        message.sequence = [2]


def test_a_received_sequence_is_a_zero_copy_view_printed_as_rclpy_prints_it() -> None:
    image_type = registry().get("sensor_msgs/msg/Image")
    data = np.arange(4, dtype=np.uint8)
    message = freeze(registry().deserialize(registry().serialize(image_type(data=data)), "sensor_msgs/msg/Image"))
    plain = message.data
    received(message)
    assert type(message.data) is SequenceView and repr(message.data) == "array('B', [0, 1, 2, 3])"
    assert np.shares_memory(message.data, plain)
    with pytest.raises(ReadOnlyMessageError):
        message.data = [1]
    reply = flavoured(image_type)()
    reply.data = message.data  # stored as the plain array: the compiled codec takes it
    assert type(copy(reply).data) is np.ndarray


def test_nested_sequences_are_shown_too() -> None:
    message_type = registry().get("example_interfaces/action/Fibonacci_FeedbackMessage")
    message = freeze(message_type())
    received(message)
    assert repr(message.feedback.sequence) == "array('i')"


def test_rospy_code_sees_ros1_header_seq_and_stamp_accessors() -> None:
    """rospy's view of ROS 2's messages: header.seq (0 outside a callback or publish; what a subscription
    counts inside one, see test_rospy), stamp.secs / nsecs / to_sec() / to_nsec()."""
    import hetros.compat.rospy as rospy_shim

    header = registry().get("std_msgs/msg/Header")()
    assert header.seq == 0
    header.seq = 3  # rospy code may write it; a publisher writes its own count
    assert header.seq == 3
    header.stamp.sec, header.stamp.nanosec = 12, 500_000_000
    assert (header.stamp.secs, header.stamp.nsecs) == (12, 500_000_000)
    assert header.stamp.to_sec() == 12.5 and header.stamp.to_nsec() == 12_500_000_000
    duration = registry().get("builtin_interfaces/msg/Duration")(sec=1, nanosec=2)
    assert duration.to_nsec() == 1_000_000_002
    # rospy.Time and Duration are stamps themselves: header.stamp = rospy.Time(...) goes into the message
    header.stamp = rospy_shim.Time(3, 5)
    assert (header.stamp.sec, header.stamp.nanosec) == (3, 5)
    later = rospy_shim.Time(4) + rospy_shim.Duration(0.5)
    assert later.to_nsec() == 4_500_000_000 and (later - header.stamp).to_sec() == pytest.approx(1.499999995)
    assert header.stamp < later and not later.is_zero()


def test_an_async_callback_runs_to_its_end_awaiting_futures() -> None:
    later = Future()

    async def execute() -> int:
        return int(await later) + 1

    threading.Timer(0.05, later.set_result, args=(41,)).start()
    assert run_to_end(execute(), threading.Event()) == 42


def test_a_futures_callbacks_run_where_it_schedules_them() -> None:
    ran: list[str] = []
    queued: list[object] = []
    future = Future(schedule=queued.append)
    future.add_done_callback(lambda f: ran.append(f.result()))
    future.set_result("done")
    assert ran == [] and len(queued) == 1
    queued[0]()  # type: ignore[operator]
    assert ran == ["done"]


def test_an_rclpy_profile_keeps_its_deadline_lifespan_and_liveliness() -> None:
    from hetros.compat.rclpy.qos import LivelinessPolicy, QoSProfile, to_hetros
    from hetros.runtime import Duration

    profile = QoSProfile(depth=10, deadline=Duration(seconds=0.6), lifespan=Duration(seconds=2),
                         liveliness=LivelinessPolicy.MANUAL_BY_TOPIC, liveliness_lease_duration=Duration(seconds=1))
    qos = to_hetros(profile)
    assert qos is not None
    assert (qos.deadline, qos.lifespan, qos.liveliness, qos.lease_duration) == (0.6, 2.0, "manual_by_topic", 1.0)
    assert to_hetros(QoSProfile(depth=5, deadline=Duration())).deadline is None  # zero: infinite, as ROS 2


def test_without_a_callback_each_side_warns_of_incompatible_qos_as_rclpy_does(caplog: pytest.LogCaptureFixture) -> None:
    from hetros import IncompatibleQosStatus
    from hetros.compat.rclpy.event_handler import incompatible_qos_handler
    from hetros.compat.rclpy.logging import RcutilsLogger

    for publisher, told in ((True, "New subscription discovered on topic '/t', requesting incompatible QoS. No "
                                   "messages will be sent to it. Last incompatible policy: RELIABILITY"),
                            (False, "New publisher discovered on topic '/t', offering incompatible QoS. No "
                                    "messages will be received from it. Last incompatible policy: DURABILITY")):
        report = incompatible_qos_handler(None, RcutilsLogger("n"), "/t", publisher=publisher)
        assert report is not None
        caplog.clear()
        with caplog.at_level("WARNING"):
            report(IncompatibleQosStatus(1, 1, "reliability" if publisher else "durability"))
        assert [record.getMessage() for record in caplog.records] == [told]


@pytest.mark.parametrize("wrong", ["hello", None, 5])
def test_rclpy_code_handing_over_something_not_a_message_is_told_where_and_what_type(wrong: object) -> None:
    """rclpy raises TypeError for a publish, a request or a goal of the wrong type; the shim's TopicTypeError is
    one, and says what the topic, service or action carries (the copy rclpy code's hand-over makes must not
    fail first with an AttributeError)."""
    from hetros import Node, TopicTypeError
    from hetros.compat.rclpy.action.client import ActionClient
    from hetros.compat.rclpy.node import Node as RclpyNode
    from hetros.runtime import ros_main

    types = registry()
    hetros = Node("talker")
    try:
        with ros_main(hetros):
            node = RclpyNode("talker")
            hand_overs = [
                (node.create_publisher(types.get("std_msgs/msg/String"), "/chatter", 10).publish,
                 "topic /chatter carries std_msgs/msg/String", "String"),
                (node.create_client(types.get_service("example_interfaces/srv/AddTwoInts"), "/add").call_async,
                 "a request of service /add carries example_interfaces/srv/AddTwoInts_Request", "AddTwoInts_Request"),
                (ActionClient(node, types.get_action("example_interfaces/action/Fibonacci"), "/fib").send_goal_async,
                 "a goal of action /fib carries example_interfaces/action/Fibonacci_Goal", "Fibonacci_Goal"),
            ]
            for hand_over, carries, short in hand_overs:
                with pytest.raises(TopicTypeError, match=rf"{carries}, not {type(wrong).__name__}; "
                                                         rf"construct a {short}") as raised:
                    hand_over(wrong)
                assert isinstance(raised.value, TypeError)
    finally:
        hetros.close()


def test_rclpy_publish_keeps_the_callers_message_unless_it_must_copy_into_numpy() -> None:
    """The shims publish a message as it is (``keep``: the transports serialize it, the caller keeps it)
    where its numeric sequences are numpy arrays; a sequence rclpy-style in an ``array.array``, or numeric
    sequences inside nested messages, go through a copy into hetros's own arrays."""
    from hetros.compat._flavour import flavoured, keepable

    image = flavoured(registry().get("sensor_msgs/msg/Image"))
    msg = image()
    msg.data = np.arange(4, dtype=np.uint8)
    assert keepable(image)(msg)
    msg.data = [1, 2]  # rclpy makes it an array.array
    assert not keepable(image)(msg)
    assert keepable(flavoured(registry().get("std_msgs/msg/String")))(None)  # no sequences: always
    assert not keepable(flavoured(registry().get("trajectory_msgs/msg/JointTrajectory")))(None)
    assert not keepable(str)("not a message")  # the copy says what the topic carries


def test_a_rospy_node_on_one_core_lets_its_callback_thread_finish_before_its_main_thread_runs() -> None:
    """Once a rospy node's callback thread runs, its main thread (here, the thread that called init_node)
    runs SCHED_BATCH when it has one core: a callback that wakes it is not preempted holding the GIL. The
    callback thread keeps the default policy, and a callback that sets an event reaches the waiting thread.
    Its hot spin hands the GIL over at every poll while the main thread runs beside it, every few polls
    once the main thread only waits in rospy.spin()."""
    import hetros.compat.rospy as rospy_shim
    from hetros import Node
    from hetros.runtime import ros_main
    from hetros.runtime._executor import SPARSE_YIELD

    hetros = Node("listener")
    seen: dict[str, int] = {}
    heard = threading.Event()

    def main() -> None:
        os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[:1])
        with ros_main(hetros):
            rospy_shim.init_node("listener")
            string = registry().get("std_msgs/msg/String")
            rospy_shim.Subscriber("/chatter", string, lambda message: heard.set())
            publisher = rospy_shim.Publisher("/chatter", string, queue_size=1)
            seen["main"] = os.sched_getscheduler(0)
            state = rospy_shim._state()
            assert state.spinner is not None and state.spinner.native_id is not None
            seen["callbacks"] = os.sched_getscheduler(state.spinner.native_id)
            publisher.publish(string(data="hi"))
            assert heard.wait(10.0)
            seen["yield_every"] = hetros.executor.yield_every

            def while_spinning() -> None:  # rospy.spin(): the callbacks' hot spin need not yield at every poll
                deadline = time.monotonic() + 10.0
                while hetros.executor.yield_every == 1 and time.monotonic() < deadline:
                    time.sleep(0.01)
                seen["yield_every_in_spin"] = hetros.executor.yield_every
                with ros_main(hetros):  # rospy calls from a thread of the node's own
                    rospy_shim.signal_shutdown("done")

            threading.Thread(target=while_spinning, daemon=True).start()
            rospy_shim.spin()

    try:
        thread = threading.Thread(target=main, daemon=True)  # a failure here fails the test, not the run
        thread.start()
        thread.join(30.0)
    finally:
        hetros.close()
    assert seen == {"main": os.SCHED_BATCH, "callbacks": os.SCHED_OTHER, "yield_every": 1,
                    "yield_every_in_spin": SPARSE_YIELD}
    assert os.sched_getscheduler(0) == os.SCHED_OTHER
