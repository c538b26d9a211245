"""The bags of the ROS world, read as rosbag2 and rosbag write them.

A bag is a rosbag2 folder (``metadata.yaml`` naming its files, its storage, its compression and what
each topic holds), or one file: MCAP (``.mcap``), sqlite3 (``.db3``) or a ROS 1 bag (``.bag``). Each is
read through the library that maintains its format: ``mcap`` (with ``zstandard`` and ``lz4`` for
compressed chunks), Python's ``sqlite3``, ``zstandard`` for rosbag2's file and message compression, and
rosbags for ROS 1 bags, whose payloads it turns into CDR with the message definitions the bag carries.
rosbags' rosbag2 reader is not used for folders: it matches a folder's topics to its storage's by their
QoS text, and rosbag2's own older bags (metadata version 4) then give no message at all.

What a bag holds comes out as ROS 2 CDR bytes per topic, in time order across split files.
"""

from __future__ import annotations

import contextlib
import heapq
import shutil
import sqlite3
import tempfile
from collections.abc import Iterator
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..._errors import InspectError
from ..._files import check_regular, load_yaml

Message = tuple[str, int, bytes]  # (topic, log time in ns, CDR bytes)
_STORAGES = {".mcap": "mcap", ".db3": "sqlite3", ".bag": "rosbag1"}


@dataclass(frozen=True)
class BagTopic:
    name: str
    type: str
    count: int
    serialization: str = "cdr"


class Bag:
    """One bag, open for reading: its topics, its time span, its messages."""

    def __init__(self, path: Path) -> None:
        if not path.exists():
            raise InspectError(f"{path} does not exist")
        self.path = path
        self.compression = ("", "")  # (mode: file | message, format: zstd)
        self.metadata: dict[str, Any] | None = None
        self._scratch: Path | None = None  # where file-compressed storage is unpacked while open
        self._ros1: Any = None
        if path.is_dir():
            self._open_folder(path)
        else:
            check_regular(path, "bag", error=InspectError)
            self.storage = _storage_of(path)
            self.files = [path]
        self.topics = self._topics()

    def _open_folder(self, path: Path) -> None:
        meta_path = path / "metadata.yaml"
        if not meta_path.is_file():
            files = sorted(f for f in path.iterdir() if f.suffix in _STORAGES)
            if not files:
                raise InspectError(f"{path}: neither a metadata.yaml nor a bag file (.mcap, .db3, .bag) in it")
            self.storage, self.files = _storage_of(files[0]), files
            return
        document = load_yaml(meta_path, "rosbag2 metadata", error=InspectError)
        try:
            info = document["rosbag2_bagfile_information"]
            self.storage = str(info["storage_identifier"])
            relative = [str(name) for name in info["relative_file_paths"]]
        except (KeyError, TypeError) as exc:
            raise InspectError(f"{meta_path}: not rosbag2 metadata ({type(exc).__name__}: {exc}); it needs "
                               "rosbag2_bagfile_information with storage_identifier and relative_file_paths") from None
        if self.storage not in ("mcap", "sqlite3"):
            raise InspectError(f"{meta_path}: storage_identifier {self.storage!r}: hetros reads mcap and sqlite3 bags")
        self.metadata = info
        self.compression = (str(info.get("compression_mode") or "").lower(),
                            str(info.get("compression_format") or "").lower())
        if self.compression[0] and self.compression != ("file", "zstd") and self.compression != ("message", "zstd"):
            raise InspectError(f"{meta_path}: compression {self.compression[0]}/{self.compression[1]}: rosbag2 "
                               "compresses files or messages with zstd, which is what hetros reads")
        # version 4 and later name files relative to the folder; older ones relative to its parent
        self.files = []
        for name in relative:
            file = path / Path(name).name if not (path / name).exists() else path / name
            if not file.is_file():
                raise InspectError(f"{meta_path}: relative_file_paths names {name}, which is not in {path}")
            self.files.append(file)

    # -- what it holds -----------------------------------------------------------------------

    def _topics(self) -> dict[str, BagTopic]:
        if self.metadata is not None:
            found: dict[str, BagTopic] = {}
            for entry in self.metadata.get("topics_with_message_count") or []:
                topic = entry["topic_metadata"]
                found[topic["name"]] = BagTopic(topic["name"], topic["type"], int(entry["message_count"]),
                                                topic.get("serialization_format", "cdr"))
            return found
        counted: dict[str, list[Any]] = {}
        for file in self.files:
            for name, msgtype, count in self._file_topics(file):
                entry = counted.setdefault(name, [msgtype, 0])
                entry[1] += count
        return {name: BagTopic(name, msgtype, count) for name, (msgtype, count) in counted.items()}

    def _file_topics(self, file: Path) -> Iterator[tuple[str, str, int]]:
        if self.storage == "mcap":
            with self._mcap(file) as reader:
                summary = reader.get_summary()
            if summary is None:
                return
            counts = summary.statistics.channel_message_counts if summary.statistics else {}
            for channel in summary.channels.values():
                schema = summary.schemas.get(channel.schema_id)
                yield channel.topic, schema.name if schema else "", counts.get(channel.id, 0)
        elif self.storage == "sqlite3":
            with closing(self._database(file)) as db:
                yield from db.execute("SELECT topics.name, topics.type, COUNT(messages.id) FROM topics LEFT JOIN "
                                      "messages ON messages.topic_id = topics.id GROUP BY topics.id")
        else:
            reader = self._ros1_reader()
            for connection in reader.connections:
                yield connection.topic, connection.msgtype, connection.msgcount

    def span(self) -> tuple[int, int] | None:
        """(start, duration) in ns: the metadata's, else the messages'."""
        if self.metadata is not None and "starting_time" in self.metadata:
            return (int(self.metadata["starting_time"]["nanoseconds_since_epoch"]),
                    int(self.metadata["duration"]["nanoseconds"]))
        first = last = None
        for _topic, stamp, _data in self.messages(None):
            first = stamp if first is None else first
            last = stamp
        return None if first is None or last is None else (first, last - first)

    def messages(self, topics: set[str] | None) -> Iterator[Message]:
        """(topic, log time, CDR bytes) of ``topics`` (all with None), in time order across the files."""
        streams = [self._file_messages(file, topics) for file in self.files]
        merged = streams[0] if len(streams) == 1 else heapq.merge(*streams, key=lambda message: message[1])
        if self.compression[0] == "message":
            import zstandard

            decompressor = zstandard.ZstdDecompressor()
            for topic, stamp, data in merged:
                yield topic, stamp, decompressor.decompressobj().decompress(data)
            return
        yield from merged

    def _file_messages(self, file: Path, topics: set[str] | None) -> Iterator[Message]:
        if self.storage == "mcap":
            with self._mcap(file) as reader:
                for _schema, channel, message in reader.iter_messages(topics=None if topics is None else
                                                                      sorted(topics)):
                    yield channel.topic, message.log_time, message.data
        elif self.storage == "sqlite3":
            with closing(self._database(file)) as db:
                rows = db.execute("SELECT topics.name, messages.timestamp, messages.data FROM messages JOIN topics "
                                  "ON messages.topic_id = topics.id ORDER BY messages.timestamp")
                for name, stamp, data in rows:
                    if topics is None or name in topics:
                        yield name, stamp, bytes(data)
        else:
            yield from self._ros1_messages(topics)

    # -- the formats ---------------------------------------------------------------------------

    @contextlib.contextmanager
    def _mcap(self, file: Path) -> Iterator[Any]:
        """The mcap library's reader of ``file``; whatever it raises on bytes it cannot read (its own
        McapError, and struct, zstd, lz4 and decode errors from inside it) ends as one InspectError."""
        from mcap.reader import make_reader

        with self._unpacked(file).open("rb") as stream:
            try:
                yield make_reader(stream)
            except InspectError:
                raise
            except Exception as exc:  # a third-party parser's errors are not one tree
                raise InspectError(f"{file}: the mcap library cannot read it ({type(exc).__name__}: {exc}); is it "
                                   "an MCAP file whole?") from None

    def _unpacked(self, file: Path) -> Path:
        """``file`` as it is read: a file rosbag2 compressed whole (``x.mcap.zstd``) unpacked beside the others
        in a scratch folder removed on close."""
        if self.compression[0] != "file":
            return file
        import zstandard

        if self._scratch is None:
            self._scratch = Path(tempfile.mkdtemp(prefix="hetros-bag-"))
        target = self._scratch / file.name.removesuffix(".zstd")
        if not target.exists():
            with file.open("rb") as source, target.open("wb") as sink:
                zstandard.ZstdDecompressor().copy_stream(source, sink)
        return target

    def _database(self, file: Path) -> sqlite3.Connection:
        unpacked = self._unpacked(file)
        try:
            db = sqlite3.connect(f"{unpacked.resolve().as_uri()}?mode=ro", uri=True)
            db.execute("SELECT name, type FROM topics LIMIT 1")
        except sqlite3.Error as exc:
            raise InspectError(f"{file}: not a rosbag2 sqlite3 storage ({exc})") from None
        return db

    def _ros1_reader(self) -> Any:
        if self._ros1 is None:
            from rosbags.rosbag1 import Reader

            try:
                self._ros1 = Reader(self.files[0])
                self._ros1.open()
            except Exception as exc:  # rosbags raises its own errors for what it cannot read
                raise InspectError(f"{self.files[0]}: not a ROS 1 bag rosbags can read "
                                   f"({type(exc).__name__}: {exc})") from None
        return self._ros1

    def _ros1_messages(self, topics: set[str] | None) -> Iterator[Message]:
        """A ROS 1 bag's messages, each turned into CDR with the definitions the bag carries."""
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        reader = self._ros1_reader()
        store = get_typestore(Stores.EMPTY)
        for connection in reader.connections:
            if connection.msgtype not in store.types:
                store.register(get_types_from_msg(connection.msgdef.data, connection.msgtype))
        wanted = [c for c in reader.connections if topics is None or c.topic in topics]
        if not wanted:
            return
        for connection, stamp, data in reader.messages(connections=wanted):
            yield connection.topic, stamp, bytes(store.ros1_to_cdr(data, connection.msgtype))

    def close(self) -> None:
        if self._ros1 is not None:
            self._ros1.close()
            self._ros1 = None
        if self._scratch is not None:
            shutil.rmtree(self._scratch, ignore_errors=True)
            self._scratch = None

    def __enter__(self) -> Bag:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()


def _storage_of(file: Path) -> str:
    storage = _STORAGES.get(file.suffix)
    if storage is None:
        raise InspectError(f"{file}: not a bag hetros reads (a rosbag2 folder, or a .mcap, .db3 or .bag file)")
    return storage
