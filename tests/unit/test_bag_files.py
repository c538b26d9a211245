"""Bags of the ROS world (``hetros.launch.observe._bagfiles.Bag``), read against what wrote them:
rosbag2's own test bags (tests/data/rosbag2) give what their metadata.yaml says, counted from the
messages themselves; bags rosbags writes compressed (file and message zstd) and ROS 1 bags read back
message for message."""

from __future__ import annotations

import subprocess
import textwrap
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import yaml
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from hetros import InspectError
from hetros.launch import recording_info
from hetros.launch.observe._bagfiles import Bag

BAGS = Path(__file__).resolve().parents[1] / "data" / "rosbag2"
STORE = get_typestore(Stores.ROS2_HUMBLE)
String = STORE.types["std_msgs/msg/String"]


def _metadata(folder: Path) -> dict[str, object]:
    info: dict[str, object] = yaml.safe_load((folder / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    return info


@pytest.mark.parametrize("bag", ["mcap/talker", "mcap/wbag", "sqlite3/talker", "sqlite3/wbag"])
def test_rosbag2s_own_bags_hold_what_their_metadata_says(bag: str) -> None:
    folder = BAGS / bag
    info = _metadata(folder)
    expected = {entry["topic_metadata"]["name"]: (entry["topic_metadata"]["type"], entry["message_count"])
                for entry in info["topics_with_message_count"]}  # type: ignore[attr-defined]
    with Bag(folder) as read:
        assert read.storage == info["storage_identifier"]
        assert [f.name for f in read.files] == [Path(p).name for p in info["relative_file_paths"]]  # type: ignore[attr-defined]
        stamps = []
        counted: Counter[str] = Counter()
        for topic, stamp, data in read.messages(None):
            counted[topic] += 1
            stamps.append(stamp)
            assert data
        assert stamps == sorted(stamps)  # in time order across the split files
        assert {name: (t.type, t.count) for name, t in read.topics.items()} == expected
        assert {name: counted[name] for name in expected} == {name: n for name, (_, n) in expected.items()}
        assert read.span() == (info["starting_time"]["nanoseconds_since_epoch"],  # type: ignore[index]
                               info["duration"]["nanoseconds"])  # type: ignore[index]
    text = recording_info(folder)
    assert f"Messages:          {info['message_count']}" in text


def test_the_talker_bags_strings_decode_in_order() -> None:
    for storage in ("mcap", "sqlite3"):
        with Bag(BAGS / storage / "talker") as read:
            said = [STORE.deserialize_cdr(data, "std_msgs/msg/String").data
                    for _topic, _stamp, data in read.messages({"/topic"})]
        assert said == [f"Hello, world! {i}" for i in range(10)], said


def _written(tmp_path: Path, name: str, mode: str | None) -> Path:
    folder = tmp_path / name
    writer = Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP)
    if mode is not None:
        writer.set_compression(CompressionMode[mode.upper()], CompressionFormat.ZSTD)
    with writer:
        connection = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=STORE)
        for i in range(25):
            writer.write(connection, 1_000 + i, STORE.serialize_cdr(String(data=f"hello {i}"), "std_msgs/msg/String"))
    return folder


@pytest.mark.parametrize("mode", [None, "file", "message"])
def test_a_compressed_bag_reads_back_message_for_message(mode: str | None, tmp_path: Path) -> None:
    folder = _written(tmp_path, f"bag_{mode}", mode)
    with Bag(folder) as read:
        assert read.compression == ((mode or ""), "zstd" if mode else "")
        said = [(stamp, STORE.deserialize_cdr(data, "std_msgs/msg/String").data)
                for _topic, stamp, data in read.messages(None)]
    assert said == [(1_000 + i, f"hello {i}") for i in range(25)]


def test_a_ros1_bag_reads_as_cdr(tmp_path: Path) -> None:
    ros1 = get_typestore(Stores.ROS1_NOETIC)
    path = tmp_path / "chatter.bag"
    with Ros1Writer(path) as writer:
        connection = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=ros1)
        for i in range(5):
            writer.write(connection, 2_000 + i, ros1.serialize_ros1(ros1.types["std_msgs/msg/String"](data=f"hi {i}"),
                                                                    "std_msgs/msg/String"))
    with Bag(path) as read:
        assert read.storage == "rosbag1" and read.topics["/chatter"].type == "std_msgs/msg/String"
        said = [STORE.deserialize_cdr(data, "std_msgs/msg/String").data for _t, _s, data in read.messages(None)]
    assert said == [f"hi {i}" for i in range(5)]


def test_a_ros1_bag_of_a_type_hetros_does_not_know_reads_from_its_own_definitions(tmp_path: Path) -> None:
    """No .msg file of ``rover_msgs/Wheel`` exists anywhere hetros looks: the bag's connection record carries
    the definition, and that is what turns its messages into CDR."""
    from rosbags.typesys import get_types_from_msg

    definition = "string name\nfloat64 speed\nint32[] ticks\n"
    ros1 = get_typestore(Stores.ROS1_NOETIC)
    ros1.register(get_types_from_msg(definition, "rover_msgs/msg/Wheel"))
    wheel = ros1.types["rover_msgs/msg/Wheel"]
    path = tmp_path / "wheels.bag"
    with Ros1Writer(path) as writer:
        connection = writer.add_connection("/wheel", "rover_msgs/msg/Wheel", typestore=ros1)
        for i in range(3):
            message = wheel(name=f"w{i}", speed=0.5 * i, ticks=np.array([i, i + 1], dtype=np.int32))
            writer.write(connection, 10 + i, ros1.serialize_ros1(message, "rover_msgs/msg/Wheel"))
    reader = get_typestore(Stores.EMPTY)
    reader.register(get_types_from_msg(definition, "rover_msgs/msg/Wheel"))
    with Bag(path) as read:
        assert read.topics["/wheel"].type == "rover_msgs/msg/Wheel"
        got = [reader.deserialize_cdr(data, "rover_msgs/msg/Wheel") for _t, _s, data in read.messages(None)]
    assert [(m.name, m.speed, m.ticks.tolist()) for m in got] == [(f"w{i}", 0.5 * i, [i, i + 1]) for i in range(3)]


@pytest.mark.parametrize(("make", "words"), [
    (lambda p: p / "missing", "does not exist"),
    (lambda p: (p / "x.txt").write_text("x") and p / "x.txt", "not a bag hetros reads"),
    (lambda p: (p / "metadata.yaml").write_text("a: [") and p, "rosbag2 metadata .* is not valid YAML"),
    (lambda p: (p / "metadata.yaml").write_text(
        "rosbag2_bagfile_information: {storage_identifier: mcap, relative_file_paths: [gone.mcap]}") and p,
     "names gone.mcap, which is not in"),
    (lambda p: (p / "broken.db3").write_bytes(b"not sqlite" * 100) and p / "broken.db3",
     "not a rosbag2 sqlite3 storage"),
])
def test_what_is_not_a_bag_is_named(make: object, words: str, tmp_path: Path) -> None:
    path = make(tmp_path)  # type: ignore[operator]
    with pytest.raises(InspectError, match=words):
        with Bag(path) as read:
            list(read.messages(None))


@pytest.mark.skipif(subprocess.run(["/usr/bin/python3", "-c", "import rosbag, std_msgs.msg"], capture_output=True,
                                   check=False).returncode != 0, reason="Debian's python3-rosbag is not installed")
def test_a_bag_debians_rosbag_writes_reads_message_for_message(tmp_path: Path) -> None:
    path = tmp_path / "debian.bag"
    subprocess.run(["/usr/bin/python3", "-c", textwrap.dedent(f"""\
        import rosbag, rospy
        from std_msgs.msg import String
        with rosbag.Bag({str(path)!r}, 'w') as bag:
            for i in range(7):
                bag.write('/chatter', String(data='from rosbag %d' % i), rospy.Time(100, i * 1000))
        """)], check=True, capture_output=True)
    with Bag(path) as read:
        assert {name: (t.type, t.count) for name, t in read.topics.items()} == {"/chatter": ("std_msgs/msg/String", 7)}
        got = [(stamp, STORE.deserialize_cdr(data, "std_msgs/msg/String").data)
               for _t, stamp, data in read.messages(None)]
    assert got == [(100_000_000_000 + i * 1000, f"from rosbag {i}") for i in range(7)]


def test_rosbag2s_qos_override_file_reads_as_the_qos_it_names(tmp_path: Path) -> None:
    """The file `ros2 bag play --qos-profile-overrides-path` takes: rosbag2's words, its infinite
    duration ({sec: 2147483647, nsec: 4294967295}) and system_default kept as hetros's default."""
    from hetros.launch.observe._bag import read_qos_overrides

    path = tmp_path / "overrides.yaml"
    path.write_text(textwrap.dedent("""\
        /scan:
          history: keep_last
          depth: 5
          reliability: best_effort
          durability: system_default
          deadline: {sec: 2147483647, nsec: 4294967295}
          lifespan: {sec: 1, nsec: 500000000}
          liveliness: automatic
          liveliness_lease_duration: {sec: 0, nsec: 0}
          avoid_ros_namespace_conventions: false
        /map: {durability: transient_local, history: keep_last, depth: 1}
        """))
    found = read_qos_overrides(path)
    assert (found["/scan"].reliability, found["/scan"].history, found["/scan"].depth) == ("best_effort", "keep_last", 5)
    assert found["/scan"].durability == "volatile" and found["/scan"].deadline is None
    assert found["/scan"].lifespan == 1.5 and found["/scan"].lease_duration is None
    assert found["/map"].keeps_history and found["/map"].depth == 1


@pytest.mark.parametrize(("text", "words"), [
    ("/a: {reliability: sometimes}", "reliability must be"),
    ("/a: {depht: 3}", r"/a\.depht is not a QoS policy rosbag2 overrides"),
    ("/a: {deadline: 2.5}", r"/a\.deadline must be \{sec: N, nsec: N\}"),
    ("/a: keep_last", "must map to a profile"),
    ("- /a", "maps each topic to its profile"),
    ("/a: {depth: [", "is not valid YAML"),
])
def test_a_bad_qos_override_file_is_named(text: str, words: str, tmp_path: Path) -> None:
    from hetros.launch.observe._bag import read_qos_overrides

    path = tmp_path / "overrides.yaml"
    path.write_text(text)
    with pytest.raises(InspectError, match=words):
        read_qos_overrides(path)
    with pytest.raises(InspectError, match="is a folder, not a file"):
        read_qos_overrides(tmp_path)
