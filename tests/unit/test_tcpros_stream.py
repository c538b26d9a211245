"""Reading TCPROS in the node's thread: frames assembled without blocking, whatever the peer does."""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Iterator

import numpy as np
import pytest

from hetros import ProtocolError
from hetros.msg import TypeRegistry
from hetros.transport import QoS
from hetros.transport.tcpros import Ros1StreamReader, Ros1Type, SocketWaiter
from hetros.transport.tcpros._stream import FrameStream

TYPES = TypeRegistry()
STRING = Ros1Type(TYPES, "std_msgs/msg/String")


def frame(payload: bytes) -> bytes:
    return struct.pack("<I", len(payload)) + payload


def string_frame(text: str) -> bytes:
    return frame(bytes(STRING.serialize(TYPES.get("std_msgs/msg/String")(data=text))))


@pytest.fixture
def pair() -> Iterator[tuple[socket.socket, socket.socket]]:
    ours, theirs = socket.socketpair()
    yield ours, theirs
    ours.close()
    theirs.close()


def test_a_frame_sent_byte_by_byte_comes_out_whole_and_only_when_complete(
        pair: tuple[socket.socket, socket.socket]) -> None:
    ours, theirs = pair
    stream = FrameStream(ours, "peer", 1 << 20)
    data = frame(b"hello") + frame(b"") + frame(b"world!")
    for byte in data[:-1]:
        theirs.send(bytes([byte]))
        got = stream.next_frame()
        assert got in (None, b"hello", b"")
    theirs.send(data[-1:])
    assert stream.next_frame() == b"world!"
    assert stream.next_frame() is None


def test_large_frames_arrive_in_pieces_into_memory_of_their_own(pair: tuple[socket.socket, socket.socket]) -> None:
    ours, theirs = pair
    stream = FrameStream(ours, "peer", 1 << 24)
    payload = np.random.default_rng(1).integers(0, 256, 3 << 20, np.uint8).tobytes()
    data = frame(b"small") + frame(payload) + frame(b"after")
    frames: list[bytes] = []
    sender = threading.Thread(target=theirs.sendall, args=(data,))
    sender.start()
    while len(frames) < 3:
        got = stream.next_frame()
        if got is not None:
            frames.append(bytes(got))
    sender.join()
    assert frames == [b"small", payload, b"after"]


def test_a_lying_length_is_refused_and_a_closed_peer_is_seen(pair: tuple[socket.socket, socket.socket]) -> None:
    ours, theirs = pair
    stream = FrameStream(ours, "ROS 1 publisher x", 1 << 20)
    theirs.send(struct.pack("<I", 0xFFFFFFFF))
    with pytest.raises(ProtocolError, match=r"ROS 1 publisher x: a frame announces 4294967295 bytes"):
        stream.next_frame()
    other, gone = socket.socketpair()
    closed = FrameStream(other, "peer", 1 << 20)
    gone.send(frame(b"last")[:6])
    gone.close()
    with pytest.raises(ConnectionError, match="peer closed the connection"):
        closed.next_frame()
    other.close()


def _reader(qos: QoS) -> tuple[Ros1StreamReader, SocketWaiter, list[int], socket.socket, list[int]]:
    waiter = SocketWaiter()
    woken: list[int] = []
    gone: list[int] = []
    reader = Ros1StreamReader("/chatter", STRING, qos, waiter, lambda: woken.append(1), 1 << 20)
    ours, theirs = socket.socketpair()
    reader.add(ours, "peer", lambda: gone.append(1))
    return reader, waiter, woken, theirs, gone


def test_a_reliable_reader_takes_one_frame_at_a_time_and_wakes_once_per_burst() -> None:
    reader, waiter, woken, theirs, _gone = _reader(QoS(reliability="reliable", history="keep_all"))
    waiter.poll()
    assert not woken and reader.try_take() is None
    theirs.sendall(b"".join(string_frame(f"m{i}") for i in range(5)))
    waiter.wait(1.0)
    waiter.poll()
    assert woken == [1]  # armed once: one wake-up until the reader has read everything
    assert [reader.try_take().data for _ in range(5)] == [f"m{i}" for i in range(5)]  # type: ignore[union-attr]
    assert reader.try_take() is None
    theirs.sendall(string_frame("again"))
    waiter.wait(1.0)
    assert woken == [1, 1]
    reader.close()
    waiter.close()
    theirs.close()


def test_keep_last_keeps_the_newest_and_counts_the_rest() -> None:
    reader, waiter, _woken, theirs, _gone = _reader(QoS(reliability="reliable", history="keep_last", depth=2))
    theirs.sendall(b"".join(string_frame(f"m{i}") for i in range(6)))
    waiter.wait(1.0)
    assert [reader.try_take().data for _ in range(2)] == ["m4", "m5"]  # type: ignore[union-attr]
    assert reader.try_take() is None and reader.dropped == 4
    reader.close()
    waiter.close()
    theirs.close()


def test_garbage_disconnects_the_peer_and_the_reader_goes_on() -> None:
    reader, waiter, _woken, theirs, gone = _reader(QoS())
    theirs.sendall(frame(b"\xff\xff\xff\x7f") + string_frame("never"))
    assert reader.try_take() is None
    assert gone == [1]
    ours, again = socket.socketpair()
    reader.add(ours, "second peer", lambda: None)
    again.sendall(string_frame("fine"))
    waiter.wait(1.0)
    assert reader.try_take().data == "fine"  # type: ignore[union-attr]
    reader.close()
    waiter.close()
    for sock in (theirs, again):
        sock.close()


def test_an_interrupt_ends_a_wait_and_a_closed_waiter_is_inert() -> None:
    waiter = SocketWaiter()
    threading.Timer(0.05, waiter.interrupt).start()
    waiter.wait(10.0)
    waiter.close()
    waiter.interrupt()
    waiter.wait(0.01)


def test_a_peer_trickling_a_large_frame_does_not_hold_the_reader(pair: tuple[socket.socket, socket.socket]) -> None:
    ours, theirs = pair
    stream = FrameStream(ours, "peer", 1 << 24)
    theirs.sendall(struct.pack("<I", 1 << 20) + bytes(1000))
    done = threading.Event()

    def trickle() -> None:
        while not done.wait(0.001):
            theirs.send(b"x")

    trickler = threading.Thread(target=trickle)
    trickler.start()
    try:
        assert stream.next_frame() is None
        assert trickler.is_alive()  # the read gave up while the peer was still sending
    finally:
        done.set()
        trickler.join()


def test_a_subscription_is_read_by_the_waiting_thread_with_no_reader_thread_left() -> None:
    """Through hetros' own master: connected, the connection is read only by whoever waits."""
    from hetros.transport.tcpros import Master, Ros1Peer, open_ros1_reader

    master = Master("127.0.0.1", 0)
    talker = Ros1Peer("/talker", master.uri)
    listener = Ros1Peer("/listener", master.uri)
    waiter = SocketWaiter()
    try:
        publication = talker.advertise("/chatter", STRING)
        reader = open_ros1_reader(listener, "/chatter", STRING, QoS(), waiter, lambda: None)
        message = None
        for attempt in range(200):
            publication.publish(TYPES.get("std_msgs/msg/String")(data=f"hello {attempt}"))
            waiter.wait(0.05)
            message = reader.try_take()
            if message is not None:
                break
        assert message is not None and message.data.startswith("hello")
        assert not [t for t in threading.enumerate() if t.name.startswith("hetros-ros1-in")]
        reader.close()
    finally:
        waiter.close()
        listener.close()
        talker.close()
        master.close()
