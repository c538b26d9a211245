"""A node's subscriptions to one topic share its transport reader as branches
(``hetros.runtime._endpoints.TopicReaders``): each gets every message; a full reliable branch holds the
others back (the publisher then waits, as for one slow subscriber); a keep_last branch drops its oldest."""

from __future__ import annotations

from hetros import QoS
from hetros.runtime._endpoints import Relay, TopicReaders
from hetros.transport._inproc import InprocTopic


def _shared(qos: QoS) -> tuple[InprocTopic, TopicReaders, list[str]]:
    topic = InprocTopic("/t", qos)
    woken: list[str] = []
    relay = Relay()
    relay.target = lambda: woken.append("first")
    shared = TopicReaders(topic.open_reader("node", relay), relay, lambda: woken.append("forgotten"))
    return topic, shared, woken


def test_each_branch_gets_every_message_in_order() -> None:
    topic, shared, woken = _shared(QoS(depth=8))
    branches = [shared.branch(lambda k=k: woken.append(f"b{k}"), QoS(depth=8)) for k in range(3)]
    for seq in range(5):
        topic.deliver(seq)
    assert {"b0", "b1", "b2"} <= set(woken)  # the transport's wake reaches every branch
    for branch in branches:
        assert [branch.try_take() for _ in range(6)] == [0, 1, 2, 3, 4, None]


def test_a_full_reliable_branch_holds_the_rest_back_until_it_takes() -> None:
    topic, shared, _ = _shared(QoS(depth=2))
    slow, fast = shared.branch(lambda: None, QoS(depth=2)), shared.branch(lambda: None, QoS(depth=2))
    topic.deliver(0)
    topic.deliver(1)
    assert [fast.try_take(), fast.try_take(), fast.try_take()] == [0, 1, None]  # slow still holds 0 and 1
    topic.deliver(2)
    topic.deliver(3)
    assert fast.try_take() is None and not topic.has_room()  # the publisher would now wait
    assert slow.try_take() == 0 and fast.try_take() == 2
    assert [slow.try_take(), slow.try_take(), slow.try_take(), slow.try_take()] == [1, 2, 3, None]
    assert [fast.try_take(), fast.try_take()] == [3, None] and topic.has_room()


def test_a_keep_last_branch_drops_its_oldest_and_counts_them() -> None:
    topic, shared, _ = _shared(QoS(history="keep_last", depth=2))
    keeper = shared.branch(lambda: None, QoS(history="keep_last", depth=2))
    taker = shared.branch(lambda: None, QoS(history="keep_last", depth=2))
    for seq in range(5):
        topic.deliver(seq)
        assert taker.try_take() == seq
    assert [keeper.try_take(), keeper.try_take(), keeper.try_take()] == [3, 4, None]
    assert keeper.counters()["dropped"] == 3


def test_the_transport_reader_closes_with_the_last_branch() -> None:
    _topic, shared, woken = _shared(QoS(depth=4))
    one, two = shared.branch(lambda: None, QoS(depth=4)), shared.branch(lambda: None, QoS(depth=4))
    one.close()
    assert not shared.closed
    two.close()
    assert shared.closed and "forgotten" in woken


def test_a_branch_that_still_holds_messages_after_a_take_is_woken_again() -> None:
    """A caller that takes one message per wake (the executor's polling spin) must hear that more are
    left: fill() moves everything the transport holds into the taker too, but wakes only the others."""
    topic, shared, woken = _shared(QoS(depth=8))
    taker = shared.branch(lambda: woken.append("taker"), QoS(depth=8))
    shared.branch(lambda: woken.append("other"), QoS(depth=8))
    for seq in range(3):
        topic.deliver(seq)
    woken.clear()
    assert taker.try_take() == 0
    assert woken.count("taker") == 1  # two are left in its FIFO
    assert [taker.try_take(), taker.try_take()] == [1, 2]
    assert woken.count("taker") == 2  # one more after the second take, none after the last
