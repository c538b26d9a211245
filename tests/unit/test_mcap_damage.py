"""Recordings damaged on disk: bit flips and truncations, each named, none a traceback.

A recording is written as `hetros record` writes one (rosbags' MCAP writer, then ``seal``
for the CRCs), then damaged in 120 ways; ``check`` must name each (the first bad chunk, where
a truncated file stops, or the part outside chunks that is damaged), and ``Recording`` must
play the whole chunks of each without raising, counting what it skips.
"""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from rosbags.rosbag2 import StoragePlugin, Writer

from hetros.launch.observe._bag import Recording
from hetros.launch.observe._mcap import check, seal, whole_messages
from hetros.msg import registry
from hetros.transport import MessageCodec

COUNT = 300


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("bag") / "rec"
    types = registry()
    codec = MessageCodec(types, "std_msgs/msg/String")
    writer = Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    connection = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=types.store)
    String = types.get("std_msgs/msg/String")
    for i in range(COUNT):  # 10 kB each: rosbags closes a chunk at 1 MiB, so some three chunks
        writer.write(connection, 1_000_000 * (i + 1), bytes(codec.encode(String(data=f"{i:05d}" + "x" * 10_000))))
    writer.close()
    path = folder / "rec.mcap"
    seal(path)
    return path


def test_a_sealed_recording_is_whole_and_plays_everything(recording: Path) -> None:
    found = check(recording)
    assert found.whole and found.chunks >= 3 and found.messages == COUNT, found.lines()
    assert len(list(whole_messages(recording))) == COUNT
    with Recording(recording) as played:
        assert played.topics == {"/chatter": "std_msgs/msg/String"}
        assert len(list(played.messages({"/chatter"}))) == COUNT


def _variants(size: int) -> list[tuple[str, int]]:
    rng = random.Random(8)
    flips = [("flip", rng.randrange(size)) for _ in range(80)]
    cuts = [("cut", rng.randrange(8, size - 1)) for _ in range(40)]
    return flips + cuts


def test_every_damaged_variant_is_named_and_plays_what_is_whole(recording: Path, tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    original = recording.read_bytes()
    named = 0
    for kind, at in _variants(len(original)):
        damaged = bytearray(original)
        if kind == "flip":
            damaged[at] ^= 1 << (at % 8)
        else:
            del damaged[at:]
        path = tmp_path / f"{kind}-{at}.mcap"
        path.write_bytes(damaged)
        found = check(path)
        assert not found.whole, f"{kind} at {at} went unnoticed"
        lines = found.lines()
        assert lines and all(str(path) in line for line in lines)
        if found.damaged:
            first = found.damaged[0]
            assert f"chunk {first.chunk} at offset {first.offset}" in lines[0]
        named += 1
        try:
            with Recording(path) as played:
                taken = list(played.messages(set(played.topics)))
        except Exception as exc:  # only hetros's own refusal (nothing playable) may end it
            from hetros import InspectError

            assert isinstance(exc, InspectError), f"{kind} at {at}: {type(exc).__name__}: {exc}"
            continue
        skipped = sum(d.messages or 0 for d in found.damaged)
        assert len(taken) <= COUNT and (not found.damaged or len(taken) + skipped <= COUNT)
        assert [int(bytes(data[8:13])) for _topic, _time, data in taken] == sorted(
            int(bytes(data[8:13])) for _topic, _time, data in taken)
        err = capsys.readouterr().err
        assert "Traceback" not in err
    assert named == 120
