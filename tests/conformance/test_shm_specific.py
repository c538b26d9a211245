"""What only the shared-memory transport promises: real zero copy, crash tolerance, loans."""

from __future__ import annotations

import logging
import os
import re
import signal
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hetros.msg import freeze, registry
from hetros.transport import MessageCodec, QoS, ShmDomain, remove_session_segments
from hetros.transport.shm._sample import file_prefix

from .test_transports import TYPE, ShmProcessHarness, drain, image


def shm_mappings() -> list[tuple[int, int, str]]:
    ranges = []
    for line in Path("/proc/self/maps").read_text().splitlines():
        parts = line.split()
        if len(parts) >= 6 and parts[5].startswith(f"/dev/shm/{file_prefix()}"):
            start, end = (int(x, 16) for x in parts[0].split("-"))
            ranges.append((start, end, parts[5]))
    return ranges


def in_shared_memory(array: np.ndarray[Any, Any]) -> bool:
    address = array.__array_interface__["data"][0]
    return any(start <= address < end for start, end, _ in shm_mappings())


@pytest.fixture
def pair(shm_session: str) -> Any:
    codec = MessageCodec(registry(), TYPE)
    publisher_side = ShmDomain(shm_session, "pub")
    subscriber_side = ShmDomain(shm_session, "sub")
    qos = QoS(depth=4)
    reader = subscriber_side.open_reader("/img", ["pub"], qos, codec, 0, lambda: None, "sub")
    writer = publisher_side.open_writer("/img", "pub", qos, codec)
    yield writer, reader
    reader.close()
    publisher_side.close()
    subscriber_side.close()
    remove_session_segments(shm_session)


def test_subscriber_array_is_a_read_only_view_on_shared_memory(pair: Any) -> None:
    writer, reader = pair
    payload = np.arange(3 * 1024 * 1024, dtype=np.uint32).view(np.uint8)
    writer.write(registry().get(TYPE)(width=7, data=payload))
    message = reader.try_take()
    assert message.width == 7
    assert np.array_equal(message.data, payload)
    assert in_shared_memory(message.data), "the array must be a view on the slot, not a copy"
    assert not message.data.flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        message.data[0] = 1
    kept = message.copy()
    assert kept.data.flags.writeable and not in_shared_memory(kept.data)


def test_loaned_publish_writes_in_place_and_hands_the_slot_over(pair: Any) -> None:
    writer, reader = pair
    size = 6 * 1024 * 1024
    message = writer.loan({"data": size})
    assert in_shared_memory(message.data), "a loaned array lives in the slot"
    message.data[:] = 7
    message.data[-1] = 9
    message.width = 3
    message.encoding = "mono8"
    message.header.frame_id = "camera"
    writer.write(freeze(message))
    assert message.data.size == 0, "after publish the loaned slot is no longer the publisher's"
    got = reader.try_take()
    assert (got.width, got.encoding, got.header.frame_id) == (3, "mono8", "camera")
    assert got.data.size == size and got.data[0] == 7 and got.data[-1] == 9
    assert in_shared_memory(got.data) and not got.data.flags.writeable


def test_loan_errors_name_the_fields(pair: Any) -> None:
    writer, _reader = pair
    with pytest.raises(Exception, match="loan sizes can be given for: data"):
        writer.loan({"pixels": 3})


def test_loan_with_a_replaced_array_still_arrives(pair: Any) -> None:
    writer, reader = pair
    message = writer.loan({"data": 16})
    message.data = np.full(32, 5, dtype=np.uint8)
    writer.write(freeze(message))
    got = reader.try_take()
    assert got.data.size == 32 and np.all(got.data == 5)


def test_subscriber_killed_mid_stream_does_not_hang_the_publisher(
    shm_session: str, caplog: pytest.LogCaptureFixture
) -> None:
    harness = ShmProcessHarness(QoS(depth=4, publish_timeout=20.0), shm_session)
    try:
        writer = harness.writer(0)
        survivor = harness.reader(0)
        victim = harness.reader(1)
        got: list[Any] = []
        stop = threading.Event()

        def consume() -> None:
            while not stop.is_set():
                got.extend(drain(survivor))
                time.sleep(0.002)

        consumer = threading.Thread(target=consume, daemon=True)
        consumer.start()
        for seq in range(3):
            writer.write(image(0, seq, 256))
        os.kill(victim.proc.pid, signal.SIGKILL)  # type: ignore[attr-defined]
        victim.proc.wait()  # type: ignore[attr-defined]
        start = time.monotonic()
        try:
            with caplog.at_level(logging.WARNING, logger="hetros.transport.shm"):
                for seq in range(3, 40):
                    writer.write(image(0, seq, 256))
        finally:
            elapsed = time.monotonic() - start
            # the consumer keeps draining until everything arrived (or the deadline): stopping it
            # as soon as the publisher is done would leave the last messages untaken
            deadline = time.monotonic() + 10
            while len(got) < 40 and time.monotonic() < deadline:
                time.sleep(0.01)
            stop.set()
        consumer.join()
        assert elapsed < 10, "the publisher must not wait out its timeout for a dead subscriber"
        assert any("is gone" in r.getMessage() for r in caplog.records), "the lost subscriber is reported"
        assert [m.width for m in got] == list(range(40))
    finally:
        harness.close()


def test_recycled_slots_never_leak_old_bytes_into_new_messages(pair: Any) -> None:
    """Serializers rely on zeroed padding and string terminators; slots are reused dirty."""
    writer, reader = pair
    cls = registry().get(TYPE)
    for round_ in range(3):
        for _ in range(4):
            writer.write(cls(encoding="x" * 300, data=np.full(5000, 0xFF, dtype=np.uint8)))
            assert reader.try_take().encoding == "x" * 300
        for _ in range(4):
            loaned = writer.loan({"data": 3})
            loaned.width = round_
            writer.write(freeze(loaned))
            got = reader.try_take()
            assert (got.encoding, got.header.frame_id, got.width) == ("", "", round_)
        for _ in range(4):
            writer.write(cls(width=round_))
            got = reader.try_take()
            assert (got.encoding, got.data.size) == ("", 0)


@pytest.fixture
def open_pair(shm_session: str) -> Any:
    """A writer in one domain and a reader in another, for a given type (closed afterwards)."""
    domains = [ShmDomain(shm_session, "a"), ShmDomain(shm_session, "b")]

    def make(typename: str, depth: int = 8) -> tuple[Any, Any]:
        codec = MessageCodec(registry(), typename)
        reader = domains[1].open_reader("/t", ["a"], QoS(depth=depth), codec, 0, lambda: None, "sub")
        return domains[0].open_writer("/t", "a", QoS(depth=depth), codec), reader

    yield make
    for domain in domains:
        domain.close()
    remove_session_segments(shm_session)


def test_messages_without_arrays_use_zeroed_cdr(open_pair: Any) -> None:
    writer, reader = open_pair("std_msgs/msg/String")
    string = registry().get("std_msgs/msg/String")
    for text in ["y" * 1000, "", "ab", "y" * 999, "", "z"] * 3:
        writer.write(string(data=text))
        assert reader.try_take().data == text


def test_messages_without_arrays_outlive_their_recycled_slots(open_pair: Any) -> None:
    """A String decodes into copies, so its sample goes back at once and its slot is reused:
    every message taken must still read as sent after many rounds through the same slots."""
    writer, reader = open_pair("std_msgs/msg/String", depth=4)
    string = registry().get("std_msgs/msg/String")
    kept = []
    for index in range(200):
        writer.write(string(data=f"message {index} " + "x" * (index % 37)))
        kept.append(reader.try_take())
    assert [m.data for m in kept] == [f"message {index} " + "x" * (index % 37) for index in range(200)]


def test_fixed_size_arrays_stay_inline(open_pair: Any) -> None:
    writer, reader = open_pair("geometry_msgs/msg/PoseWithCovariance", depth=2)
    cls = registry().get("geometry_msgs/msg/PoseWithCovariance")
    sent = cls(covariance=np.arange(36, dtype=np.float64))
    sent.pose.position.x = 1.5
    writer.write(sent)
    assert reader.try_take() == sent
    with pytest.raises(Exception, match="loan sizes can be given for: none"):
        writer.loan({"covariance": 36})


def test_back_pressure_wakes_the_publisher_of_its_300th_service(shm_session: str) -> None:
    """Back-channel event ids are bounded like wake ids: the 300th service of a process still wakes."""
    publishing, subscribing = ShmDomain(shm_session, "a"), ShmDomain(shm_session, "b")
    codec = MessageCodec(registry(), "std_msgs/msg/Int32")
    cls = registry().get("std_msgs/msg/Int32")
    qos = QoS(depth=1, publish_timeout=5.0)
    try:
        writers = [publishing.open_writer(f"/t{i}", "a", qos, codec) for i in range(300)]
        for writer in writers[:-1]:
            writer.write(cls(data=0))  # every service gets its publisher (and back-channel id)
        reader = subscribing.open_reader("/t299", ["a"], qos, codec, 0, lambda: None, "sub")
        writers[-1].write(cls(data=1))
        done = threading.Event()

        def second() -> None:
            writers[-1].write(cls(data=2))  # blocks: the subscriber's FIFO of depth 1 is full
            done.set()

        blocked = threading.Thread(target=second)
        blocked.start()
        assert not done.wait(0.3), "the publisher must block on the full FIFO"
        assert reader.try_take().data == 1
        assert done.wait(2.0), "taking must wake the blocked publisher"
        blocked.join()
        assert reader.try_take().data == 2
    finally:
        subscribing.close()
        publishing.close()
        remove_session_segments(shm_session)


@pytest.mark.parametrize(("layout", "body", "expected"), [
    (0, b"\x00\x01\x00\x00" + b"\xff" * 6, r"Image\.header\.stamp\.sec at offset 32 needs 12 bytes, but the message "
                                             r"ends at offset 38"),
    (0, b"\x00\x01\x00\x00" + bytes(8) + b"\xff" * 4, r"Image\.header\.frame_id at offset 40 has length 4294967295"),
    (0, b"\x01\x00\x00\x00", r"do not start with the little-endian CDR encapsulation 00 01"),
    (1, (2**31).to_bytes(4, "little") + (1).to_bytes(4, "little") + bytes(32),
     r"does not fit a 68-byte sample of sensor_msgs/msg/Image \(the table at offset 28 is damaged\)"),
    (1, bytes(4) + (2**30).to_bytes(4, "little"), r"the table at offset 28 names 1073741824 arrays"),
    (9, b"", r"unknown shared-memory layout 9 at offset 12 of the sample header"),
])
def test_damaged_samples_are_dropped_counted_and_logged(pair: Any, layout: int, body: bytes, expected: str,
                                                        caplog: pytest.LogCaptureFixture) -> None:
    """Bytes in shared memory are never trusted: a damaged sample is dropped with its offset in
    the log, counted, and the reader goes on with the next one."""
    from hetros.transport.shm._sample import HEADER

    writer, reader = pair
    service = writer._service
    sample, memory = service.loan(HEADER.size + len(body))
    memory[HEADER.size:] = body
    service.send(sample, memory, layout, 0)
    writer.write(registry().get(TYPE)(width=5))
    assert reader.try_take().width == 5
    assert reader.dropped == 1
    assert re.search(expected, caplog.text), caplog.text


@pytest.mark.parametrize(("field", "value", "expected"), [
    (5, 2**40, r"blob 0 at offset \d+ \(1099511627776 bytes\) does not fit a \d+-byte sample of sensor_msgs/msg/Image"),
    (2, 7, r"blob 7 at offset \d+ \(100000 bytes\) does not fit a \d+-byte sample"),
    (3, 61, r"the small part at offset 61 \(\d+ bytes\) does not fit"),
])
def test_a_loan_whose_table_was_damaged_in_flight_is_refused(pair: Any, field: int, value: int, expected: str,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    """A one-array split sample is decoded in one unpack when it is sound; damage to any field of
    its table (blob length, array index, small part's place) still gets the refusal naming it."""
    from hetros.transport.shm._sample import HEADER, SPLIT_ONE

    writer, reader = pair
    message = writer.loan({"data": 100_000})
    table = list(SPLIT_ONE.unpack_from(message._hetros_loan.memory, HEADER.size))
    assert table[1] == 1, "one array: the table the one-unpack decode reads"
    table[field] = value
    SPLIT_ONE.pack_into(message._hetros_loan.memory, HEADER.size, *table)
    writer.write(message)
    assert reader.try_take() is None and reader.dropped == 1
    assert re.search(expected, caplog.text), caplog.text
    sound = writer.loan({"data": 100_000})
    sound.data[:] = 7
    writer.write(sound)
    taken = reader.try_take()
    assert taken.data.size == 100_000 and int(taken.data.sum()) == 700_000 and not taken.data.flags.writeable


def test_a_gap_in_a_reliable_stream_is_reported_not_skipped(pair: Any) -> None:
    """Sequence numbers are checked on every take (compiled or not): a gap that the publisher's
    numbering then proves (the next sample goes on from the jump) raises."""
    from hetros import TransportError

    writer, reader = pair
    Image = registry().get(TYPE)
    writer.write(Image(width=1))
    assert reader.try_take().width == 1
    writer._service.next_seq += 2  # as if two samples had gone missing in iceoryx2
    writer._service.credits.publish(3)
    writer.write(Image(width=2))
    assert reader.try_take().width == 2  # a jump alone proves nothing yet
    writer.write(Image(width=3))
    with pytest.raises(TransportError, match=r"2 message\(s\) from target 'pub' \(from #2\) never reached.*"
                                             r"iceoryx2 could not deliver"):
        reader.try_take()
    writer.write(Image(width=4))  # reported once: the reader goes on
    assert reader.try_take().width == 4
    assert reader.dropped == 0


def test_a_forged_sequence_number_within_the_published_is_damage_not_loss(pair: Any,
                                                                         caplog: pytest.LogCaptureFixture) -> None:
    """A number rewritten in shared memory to one the publisher did send (so it passes the
    "beyond published" check) used to stop the graph with "never reached ... file descriptors":
    what follows shows the numbering did not jump, and the damage is counted and logged."""
    from hetros.transport.shm._sample import HEADER

    writer, reader = pair
    service = writer._service
    Image = registry().get(TYPE)
    codec = MessageCodec(registry(), TYPE)

    def send_forged(width: int) -> None:
        body = codec.encode(Image(width=width))
        sample, memory = service.loan(HEADER.size + len(body))
        memory[HEADER.size:] = body
        service.send(sample, memory, 0, 0)
        HEADER.pack_into(memory, 0, service.next_seq, 0, 0, 0)  # one ahead of its own number

    writer.write(Image(width=1))
    assert reader.try_take().width == 1
    send_forged(2)
    writer.write(Image(width=3))
    assert [reader.try_take().width, reader.try_take().width] == [2, 3]
    assert reader.try_take() is None  # the next sample settles it, or the publisher's count
    assert reader.dropped == 1
    send_forged(4)  # the last one sent: the publisher's count settles it
    assert reader.try_take().width == 4
    assert reader.try_take() is None
    assert reader.dropped == 2
    for width in range(5, 5 + 3 * 4):  # three FIFOs' worth: no credit went astray
        writer.write(Image(width=width))
        assert reader.try_take().width == width
    assert "was not the publisher's" in caplog.text and "file descriptors" not in caplog.text


@pytest.mark.parametrize("damage", ["size", "sequence"])
def test_one_damaged_header_does_not_wedge_a_reliable_reader(pair: Any, damage: str,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    """A sample whose iceoryx2 size is under hetros's header, or whose sequence number was
    overwritten, is dropped and its credit given back: later takes and the publisher go on
    (they used to raise "never reached" on every take until the publisher timed out)."""
    from hetros.transport.shm._sample import HEADER

    writer, reader = pair
    service = writer._service
    Image = registry().get(TYPE)
    if damage == "size":  # a 20-byte sample straight through iceoryx2, as a same-user process could send
        from hetros.transport.shm._iceoryx import assume_init, loan_slice

        assume_init(loan_slice(service.publisher(), HEADER.size - 8)).send()
        service.next_seq += 1
        service.credits.publish(service.next_seq - 1)
    else:
        sample, memory = service.loan(HEADER.size + 8)
        service.send(sample, memory, 0, 0)
        HEADER.pack_into(memory, 0, 2**40, 0, 0, 0)  # written into the sample after it was sent
        del sample
    for width in range(1, 4 * 4):  # four FIFOs' worth: the publisher would block on a lost credit
        writer.write(Image(width=width))
        assert reader.try_take().width == width
    assert reader.dropped == 1
    assert "dropped a damaged sample" in caplog.text


@pytest.mark.parametrize("layout", ["cdr", "split"])
def test_a_waiting_publisher_is_woken_by_the_take_that_frees_room(shm_session: str, layout: str) -> None:
    """A subscriber that finds the publisher waiting (credits 'waiting') signals it once half
    its FIFO is free, whichever path took the sample, for small messages and large loans."""
    codec = MessageCodec(registry(), TYPE)
    publishing, subscribing = ShmDomain(shm_session, "pub"), ShmDomain(shm_session, "sub")
    qos = QoS(depth=4)
    try:
        reader = subscribing.open_reader("/img", ["pub"], qos, codec, 0, lambda: None, "sub")
        writer = publishing.open_writer("/img", "pub", qos, codec)
        Image = registry().get(TYPE)

        def message(width: int) -> Any:
            if layout == "cdr":
                return Image(width=width)
            loaned = writer.loan({"data": 100_000})  # beyond the inline limit: the split layout
            loaned.width, loaned.data[-1] = width, width
            return freeze(loaned)

        for width in range(4):
            writer.write(message(width))
        woken = threading.Event()
        last = message(4)
        sent = threading.Thread(target=lambda: (writer.write(last), woken.set()), daemon=True)
        sent.start()
        time.sleep(0.2)
        assert not woken.is_set(), "a keep_all publisher must wait while the FIFO is full"
        assert writer._service.credits.waiting
        got = [reader.try_take() for _ in range(3)]
        assert woken.wait(5.0), "the takes freed room but the publisher was not woken"
        sent.join(5.0)
        got += drain(reader)
        assert [m.width for m in got] == [0, 1, 2, 3, 4]
        if layout == "split":
            assert [int(m.data[-1]) for m in got] == [0, 1, 2, 3, 4] and in_shared_memory(got[0].data)
    finally:
        subscribing.close()
        publishing.close()
        remove_session_segments(shm_session)


def test_the_compiled_hot_path_shares_the_sample_layout() -> None:
    """_cslot writes and reads the header and credits words by offset: the layout it was told."""
    from hetros.transport.shm import _hotpath
    from hetros.transport.shm._credits import Credits
    from hetros.transport.shm._sample import CDR_BODY_AT, HEADER

    assert HEADER.format == "<QIIQ4x" and CDR_BODY_AT == HEADER.size + 4 == 32
    assert (Credits.HEAD, Credits.SLOT_WORDS) == (6, 4)
    if os.environ.get("HETROS_PURE_PYTHON") == "1":
        assert _hotpath.send_cdr is None and _hotpath.take_cdr is None


@pytest.mark.parametrize("pure", ["0", "1"], ids=["compiled", "pure-python"])
@pytest.mark.parametrize(("size", "count", "past_the_segment"),
                         [(2**34, 2**32 - 1, True), (2**63, 16, True), (2**20, 2**19, False)])
def test_a_size_forged_in_shared_memory_is_dropped_not_a_crash(pure: str, size: int, count: int,
                                                                past_the_segment: bool) -> None:
    """iceoryx2's size of a sample and the array length in it, rewritten after the send: the
    reader used to view memory past the segment and die of SIGSEGV; it now drops the sample.
    A size that stays inside the segment is forged data (docs/SECURITY.md), read without harm."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).with_name("shm_tamper.py")
    env = {**os.environ, "HETROS_PURE_PYTHON": pure}
    done = subprocess.run([sys.executable, str(script), str(size), str(count)], capture_output=True, text=True,
                          timeout=60, env=env, check=False)
    assert done.returncode == 0, f"the reader died ({done.returncode}):\n{done.stderr[-3000:]}"
    outcome = json.loads(done.stdout.strip().splitlines()[-1])
    if past_the_segment:
        assert outcome == {"first": None, "sum": None, "after": 2, "dropped": 1}, (outcome, done.stderr[-2000:])
    else:
        assert outcome["after"] == 2, outcome


def test_a_slot_that_cannot_be_had_says_why(pair: Any) -> None:
    """Too many loans held, and a slot shared memory cannot hold, are two causes with two
    fixes (out of memory used to be blamed on 'unpublished loans')."""
    from hetros import TransportError
    from hetros.transport.shm._sample import MAX_LOANS

    writer, _reader = pair
    service = writer._service
    held = [service.loan(100) for _ in range(MAX_LOANS)]
    with pytest.raises(TransportError, match="unpublished loans"):
        service.loan(100)
    held.clear()
    with pytest.raises(TransportError, match="most likely full"):
        service.loan(1 << 44)
    assert not [name for name in os.listdir("/dev/shm") if name.startswith(file_prefix()) and
                os.stat(f"/dev/shm/{name}").st_size >= 1 << 40], "a failed segment growth left a file"


_CREDIT_WORDS = {"published": 0, "waiting": 1, "version": 2, "back_event": 3, "publisher_pid": 4,
                 "asserted_ns": 5, "taken": 6, "pid": 7, "wake_key": 8, "event_id": 9}


@pytest.mark.parametrize("word", sorted(_CREDIT_WORDS))
@pytest.mark.parametrize("value", [0, 2**64 - 1, 2**63 + 12345, 99_999_999])
def test_a_flipped_credits_word_never_stops_the_stream(pair: Any, word: str, value: int,
                                                        caplog: pytest.LogCaptureFixture) -> None:
    """Any process of the user can write a credits file: a word set to anything (a pid that
    ``os.kill`` cannot take, an event id iceoryx2 refuses, a count ahead of the publisher) is
    range-checked where it is read; publishing and taking go on, and what was dropped is counted."""
    writer, reader = pair
    Image = registry().get(TYPE)
    words = writer._service.credits.words
    sent = taken = 0
    for round_ in range(3):
        for _ in range(2):
            sent += 1
            writer.write(Image(width=sent))
        words[_CREDIT_WORDS[word]] = value  # between a send and its take, as a stray writer would
        while (message := reader.try_take()) is not None:
            assert message.width > taken
            taken = message.width
        assert round_ < 2 or taken == sent
    # what could not be delivered is counted and logged, never silent
    assert taken == sent or reader.dropped > 0
    assert "file descriptors" not in caplog.text
