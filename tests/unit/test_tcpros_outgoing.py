"""A ROS 1 subscriber that stops reading never freezes the publisher, nor gets a torn frame."""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Iterator

import pytest

from hetros import PublishTimeoutError
from hetros.transport import QoS
from hetros.transport.tcpros._outgoing import SubscriberLink

FRAME = struct.Struct("<II")  # length, then a sequence number as the payload's start
PAYLOAD = 20_000


def frame(seq: int, fill: bytearray | None = None) -> tuple[list[bytes | memoryview], int]:
    body = fill if fill is not None else bytearray(PAYLOAD)
    struct.pack_into("<I", body, 0, seq)
    return [struct.pack("<I", len(body)), memoryview(body)], 4 + len(body)


def read_frames(sock: socket.socket, count: int) -> list[int]:
    """Sequence numbers of ``count`` whole frames (a torn frame would misalign and fail)."""
    sock.settimeout(5.0)
    seqs = []
    for _ in range(count):
        header = sock.recv(FRAME.size, socket.MSG_WAITALL)
        length, seq = FRAME.unpack(header)
        assert length == PAYLOAD
        rest = length - 4
        while rest:
            rest -= len(sock.recv(rest))
        seqs.append(seq)
    return seqs


@pytest.fixture
def pair() -> Iterator[tuple[socket.socket, socket.socket]]:
    ours, theirs = socket.socketpair()
    ours.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
    theirs.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    yield ours, theirs
    theirs.close()


def test_a_reader_that_keeps_up_gets_every_frame(pair: tuple[socket.socket, socket.socket]) -> None:
    ours, theirs = pair
    link = SubscriberLink(ours, "/listener", "/chatter", QoS(history="keep_all", depth=4))
    got: list[int] = []
    reader = threading.Thread(target=lambda: got.extend(read_frames(theirs, 50)))
    reader.start()
    for seq in range(50):
        link.send(*frame(seq))
    reader.join()
    assert got == list(range(50))
    link.close()


def test_keep_last_drops_for_a_stalled_reader_and_never_tears_a_frame(
        pair: tuple[socket.socket, socket.socket]) -> None:
    ours, theirs = pair
    link = SubscriberLink(ours, "/listener", "/chatter", QoS(history="keep_last", depth=3))
    buffer = bytearray(PAYLOAD)
    for seq in range(40):
        link.send(*frame(seq, buffer))  # the caller reuses its buffer at once: what waits is a copy
    assert link.dropped > 0
    got = read_frames(theirs, 40 - link.dropped)
    assert got == sorted(got) and got[-3:] == [37, 38, 39]
    link.close()


def test_keep_all_holds_the_publisher_then_names_the_subscriber(pair: tuple[socket.socket, socket.socket]) -> None:
    ours, _theirs = pair
    link = SubscriberLink(ours, "/slow_listener", "/chatter", QoS(history="keep_all", depth=2, publish_timeout=0.2))
    with pytest.raises(PublishTimeoutError, match=r"/chatter: ROS 1 subscriber /slow_listener has not read"):
        for seq in range(100):
            link.send(*frame(seq))
    link.close()


def test_a_subscriber_that_left_is_reported_to_the_publication(pair: tuple[socket.socket, socket.socket]) -> None:
    ours, theirs = pair
    link = SubscriberLink(ours, "/listener", "/chatter", QoS(history="keep_last", depth=2))
    theirs.close()
    with pytest.raises(OSError):
        for seq in range(100):
            link.send(*frame(seq))
    link.close()
