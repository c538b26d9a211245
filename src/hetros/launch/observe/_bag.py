"""``hetros record`` and ``hetros play``: MCAP recordings of a running launch, played back into one.

A recording is rosbag2's MCAP storage as rosbags writes it: ROS 2 CDR payloads, ``ros2msg``
schemas, the rosbag2 metadata record inside the file. Foxglove and ``ros2 bag`` (with the MCAP
storage plugin) open it. The recorder reads the launch through taps, so a publisher never waits
for it: what the taps had to drop is counted and reported, never hidden.

Playback delivers each message to the subscriptions of its topic where they run. ``--clock``
publishes the recording's time on ``/clock`` (for ``use_sim_time`` projects); ``--lockstep``
delivers a message only when every consumer has finished the one before, at the message's own
time, so a replay gives the same outputs, bit for bit, however the graph is mapped.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..._errors import InspectError
from ..._files import load_yaml
from ..._qos import QoS
from ...plan import CLOCK_TOPIC, CLOCK_TYPE
from ._bagfiles import Bag
from ._inspect import RunningLaunch
from ._mcap import check, mcap_files, seal, whole_messages

# how often --clock publishes the recording's time between messages (ros2 bag play's default)
CLOCK_HZ = 40.0
# how long --lockstep waits for a consumer to finish one message
LOCKSTEP_PATIENCE = 60.0


@dataclass
class RecordSummary:
    path: Path
    messages: dict[str, int] = field(default_factory=dict)
    dropped: dict[str, int] = field(default_factory=dict)

    def describe(self) -> str:
        lines = [f"wrote {self.path}: {sum(self.messages.values())} messages"]
        for topic in sorted(self.messages):
            lost = self.dropped.get(topic, 0)
            note = f" ({lost} dropped by the tap: the recorder fell behind)" if lost else ""
            lines.append(f"  {topic}: {self.messages[topic]}{note}")
        return "\n".join(lines)


def recordable(launch: RunningLaunch, topics: list[str] | None) -> list[str]:
    """The topics to record: the ones named (each checked), or every topic this machine sees."""
    if topics:
        for topic in topics:
            launch.topic(topic)
        return topics
    return sorted(name for name, channel in launch.plan.channels.items()
                  if channel.kind == "topic" and "/_action/" not in name and launch.plan.tap_sites(name)[1])


def record(launch: RunningLaunch, topics: list[str], out: Path, *, duration: float | None = None,
           stop: threading.Event | None = None, attached: Callable[[], None] = lambda: None,
           compression: str = "") -> RecordSummary:
    """Record ``topics`` into ``out`` (an ``.mcap`` file, or a rosbag2 folder otherwise) until ``duration``
    passed, ``stop`` is set, or the launch ends; ``compression`` ``file`` or ``message`` compresses a
    folder's storage with zstd, as ``ros2 bag record --compression-mode`` does."""
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    if out.exists():
        raise InspectError(f"{out} exists already: hetros record does not overwrite; choose another -o")
    single = out.suffix == ".mcap"
    if compression not in ("", "file", "message"):
        raise InspectError(f"--compression-mode must be none, file or message, not {compression!r}")
    if compression and single:
        raise InspectError(f"--compression-mode {compression}: a compressed bag is a rosbag2 folder (its metadata "
                           f"says how it is compressed); give -o a folder, not {out.name}")
    # rosbags names the file after its folder, and the metadata inside names the file: a folder named
    # as the recording's stem, in a hidden one beside it, gives a file whose metadata names it truly
    scratch = out.with_name(f".{out.name}.recording")
    folder = scratch / out.stem if single else out
    if single:
        shutil.rmtree(scratch, ignore_errors=True)
        scratch.mkdir(parents=True)
    writer = Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP)
    if compression:
        writer.set_compression(CompressionMode[compression.upper()], CompressionFormat.ZSTD)
    writer.open()
    summary = RecordSummary(out)
    stop = stop or threading.Event()
    try:
        connections = {topic: writer.add_connection(topic, launch.plan.channels[topic].type,
                                                    typestore=launch.types.store,
                                                    offered_qos_profiles=[offered_qos(launch.plan.channels[topic].qos)])
                       for topic in topics}
        deadline = None if duration is None else time.monotonic() + duration
        for topic, event in launch.tap_many(topics, data=True, attached=attached):
            if event is not None and event.data is not None:
                writer.write(connections[topic], event.time_ns, event.data)
                summary.messages[topic] = summary.messages.get(topic, 0) + 1
                if event.dropped:
                    summary.dropped[topic] = summary.dropped.get(topic, 0) + event.dropped
            if stop.is_set() or (deadline is not None and time.monotonic() >= deadline):
                break
    except InspectError as exc:
        if "ended" not in str(exc):
            raise
        if not stop.is_set():  # `launch --record` stops the launch itself: nothing to say then
            print(f"the launch ended: {exc}", file=sys.stderr)
    finally:
        writer.close()
        for written in mcap_files(folder):
            seal(written)  # chunk, data and summary CRCs: `hetros play` then names damage instead of playing it
        if single:
            (folder / out.name).replace(out)
            shutil.rmtree(scratch, ignore_errors=True)
    for topic in topics:
        summary.messages.setdefault(topic, 0)
    return summary


def offered_qos(qos: QoS) -> Any:
    """A topic's QoS as rosbag2's metadata keeps it (``offered_qos_profiles``), so that ``ros2 bag play``
    offers what the recorded publishers offered."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    def span(seconds: float | None) -> QosTime:
        if seconds is None:  # rosbag2's "infinite"
            return QosTime(0x7FFFFFFF, 0xFFFFFFFF)
        return QosTime(int(seconds), round((seconds - int(seconds)) * 1e9))

    return Qos(QosHistory[qos.history.upper()], qos.depth, QosReliability[qos.reliability.upper()],
               QosDurability[qos.durability.upper()], span(qos.deadline), span(qos.lifespan),
               QosLiveliness[qos.liveliness.upper()], span(qos.lease_duration), False)


def play(launch: RunningLaunch, path: Path, *, rate: float = 1.0, loop: bool = False, clock: bool = False,
         lockstep: bool = False, topics: list[str] | None = None, start_offset: float = 0.0,
         remap: dict[str, str] | None = None, qos_overrides: Path | None = None) -> dict[str, int]:
    """Deliver a recording's messages into a running launch; the count per (launch) topic. ``start_offset``
    seconds of the recording are skipped; ``remap`` plays a recorded topic onto another (ros2 bag play's
    ``--remap old:=new``); ``qos_overrides`` (rosbag2's override file) must agree with the launch's QoS."""
    if qos_overrides is not None:
        _check_overrides(launch, read_qos_overrides(qos_overrides), qos_overrides)
    if not rate > 0:
        raise InspectError(f"--rate must be positive, not {rate!r}")
    if not (start_offset >= 0 and start_offset < float("inf")):
        raise InspectError(f"--start-offset must be zero or positive seconds, not {start_offset!r}")
    remap = dict(remap or {})
    if (clock or lockstep) and CLOCK_TOPIC not in launch.plan.channels:
        if clock:
            raise InspectError(f"--clock: launch {launch.record.session}'s project does not follow /clock; "
                               "add `use_sim_time: true` to it")
        clock = False
    elif lockstep:
        clock = True  # lockstep replays in the recording's time
    recording = Recording(path)
    with recording:
        for old in remap:
            if old not in recording.topics:
                raise InspectError(f"--remap {old}:={remap[old]}: {path} has no topic {old} (it has "
                                   f"{', '.join(sorted(recording.topics))})")
        wanted = []
        for topic, msgtype in recording.topics.items():
            if topics and topic not in topics:
                continue
            target = remap.get(topic, topic)
            channel = launch.plan.channels.get(target)
            if channel is None or channel.kind != "topic":
                print(f"skipping {topic}: launch {launch.record.session} has no topic {target}", file=sys.stderr)
                continue
            if channel.type != msgtype:
                raise InspectError(f"{path}: {topic} was recorded as {msgtype}, but the launch carries "
                                   f"{channel.type} on {target}")
            wanted.append(topic)
        if not wanted:
            raise InspectError(f"{path}: none of its topics is a topic of launch {launch.record.session}")
        counts = {remap.get(topic, topic): 0 for topic in wanted}
        skip_ns = round(start_offset * 1e9)
        span = recording.bag.span() if recording.bag is not None and recording.bag.metadata is not None else None
        clock_codec = launch.codec(CLOCK_TYPE)
        wait = LOCKSTEP_PATIENCE if lockstep else 0.0

        def tell_time(nanoseconds: int) -> None:
            message = launch.types.get(CLOCK_TYPE)(clock=launch.types.get("builtin_interfaces/msg/Time")(
                sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000))
            launch.publish_bytes(CLOCK_TOPIC, bytes(clock_codec.encode(message)), wait=wait)

        while True:
            start_wall = time.monotonic()
            first: int | None = None
            last_clock = 0.0
            begin = (span[0] if span else None)
            for topic, timestamp, data in recording.messages(set(wanted)):
                begin = timestamp if begin is None else begin
                if timestamp - begin < skip_ns:
                    continue
                topic = remap.get(topic, topic)
                first = timestamp if first is None else first
                if not lockstep:
                    due = start_wall + (timestamp - first) / 1e9 / rate
                    while (left := due - time.monotonic()) > 0:
                        if clock and time.monotonic() - last_clock >= 1.0 / CLOCK_HZ:
                            tell_time(first + int((time.monotonic() - start_wall) * rate * 1e9))
                            last_clock = time.monotonic()
                        time.sleep(min(left, 1.0 / CLOCK_HZ))
                if clock:
                    tell_time(timestamp)
                    last_clock = time.monotonic()
                reached = launch.publish_bytes(topic, bytes(data), wait=wait)
                patience = time.monotonic() + LOCKSTEP_PATIENCE
                while lockstep and not reached and time.monotonic() < patience:
                    time.sleep(0.05)  # lockstep loses nothing: wait for the consumers to subscribe
                    reached = launch.publish_bytes(topic, bytes(data), wait=wait)
                counts[topic] += 1
            if not loop:
                _settle(launch, counts)
                return counts


# how long the end of a recording waits for its consumers to handle what was played to them
SETTLE_SECONDS = 15.0


def _settle(launch: RunningLaunch, counts: dict[str, int]) -> None:
    """Return once every consumer has handled what was played to it, so that a launch stopped at the end of
    the recording (``play --launch``) does not stop a listener with the last messages untaken. A consumer
    that does not finish within SETTLE_SECONDS is named, not waited for: the recording was played."""
    for topic in counts:
        try:
            launch.settle(topic, SETTLE_SECONDS)
        except InspectError as exc:
            print(f"[play] warning: {exc}", file=sys.stderr)


# rosbag2's "infinite" duration in a QoS override file: {sec: 2147483647, nsec: 4294967295}
_INFINITE_SEC = 2147483647
_OVERRIDE_KEYS = {"history", "depth", "reliability", "durability", "deadline", "lifespan", "liveliness",
                  "liveliness_lease_duration", "avoid_ros_namespace_conventions"}


def read_qos_overrides(path: Path) -> dict[str, QoS]:
    """``ros2 bag play --qos-profile-overrides-path``'s file: topic -> the QoS the player offers, in
    rosbag2's words (``system_default`` keeps hetros's default; durations as ``{sec, nsec}``)."""
    raw = load_yaml(path, "QoS override file", error=InspectError)
    if not isinstance(raw, dict):
        raise InspectError(f"{path}: a QoS override file maps each topic to its profile, not {type(raw).__name__}")
    found: dict[str, QoS] = {}
    for topic, profile in raw.items():
        if not isinstance(profile, dict):
            raise InspectError(f"{path}: {topic} must map to a profile (reliability:, durability:, ...), "
                               f"not {profile!r}")
        unknown = sorted(set(map(str, profile)) - _OVERRIDE_KEYS)
        if unknown:
            raise InspectError(f"{path}: {topic}.{unknown[0]} is not a QoS policy rosbag2 overrides "
                               f"({', '.join(sorted(_OVERRIDE_KEYS))})")
        given: dict[str, Any] = {}
        for key in ("history", "reliability", "durability", "liveliness"):
            value = profile.get(key)
            if value is not None and value != "system_default":
                given[key] = value
        if profile.get("depth"):
            given["depth"] = profile["depth"]
        for key, field_name in (("deadline", "deadline"), ("lifespan", "lifespan"),
                                ("liveliness_lease_duration", "lease_duration")):
            if (seconds := _override_seconds(path, f"{topic}.{key}", profile.get(key))) is not None:
                given[field_name] = seconds
        try:
            found[str(topic)] = QoS(**given)
        except (TypeError, ValueError) as exc:
            raise InspectError(f"{path}: {topic}: {exc}") from None
    return found


def _override_seconds(path: Path, where: str, value: Any) -> float | None:
    if value is None:
        return None
    if not isinstance(value, dict) or set(value) - {"sec", "nsec"} or not all(
            isinstance(value.get(k, 0), int) and not isinstance(value.get(k, 0), bool) and value.get(k, 0) >= 0
            for k in ("sec", "nsec")):
        raise InspectError(f"{path}: {where} must be {{sec: N, nsec: N}} with whole non-negative numbers, "
                           f"not {value!r}")
    sec, nsec = int(value.get("sec", 0)), int(value.get("nsec", 0))
    if sec >= _INFINITE_SEC or sec == nsec == 0:
        return None  # rosbag2's infinite, or ROS 2's "default" zero
    return sec + nsec / 1e9


def _check_overrides(launch: RunningLaunch, overrides: dict[str, QoS], source: Path) -> None:
    """A running launch's transports are planned: an override must agree with what they deliver."""
    for topic, wanted in sorted(overrides.items()):
        channel = launch.plan.channels.get(topic)
        if channel is None:
            continue
        planned = channel.qos
        for policy in ("reliability", "history", "durability"):
            if getattr(wanted, policy) != getattr(planned, policy):
                raise InspectError(
                    f"{source}: {topic}.{policy} is {getattr(wanted, policy)}, but launch {launch.record.session} "
                    f"delivers {topic} {getattr(planned, policy)}; a running graph's QoS is planned, so play "
                    f"with `hetros play --launch PROJECT` to launch it with the override")


def describe_played(counts: dict[str, int]) -> str:
    return f"played {sum(counts.values())} messages: " + ", ".join(f"{t} {n}" for t, n in sorted(counts.items()))


def recording_info(path: Path) -> str:
    """What ``ros2 bag info`` prints of a bag: its files and size, its storage, its time span, and per topic
    its type and message count (a rosbag2 folder's from its metadata; a file's counted from its messages,
    so a damaged MCAP file is described as far as it is whole)."""
    with Recording(path) as recording:
        bag = recording.bag
        if bag is not None and bag.metadata is not None:
            counts = {name: topic.count for name, topic in bag.topics.items()}
            span = bag.span()
        else:
            counts = dict.fromkeys(recording.topics, 0)
            first = last = None
            for topic, stamp, _data in recording.messages(set(recording.topics)):
                counts[topic] += 1
                first = stamp if first is None else min(first, stamp)
                last = stamp if last is None else max(last, stamp)
            span = None if first is None or last is None else (first, last - first)
        files = bag.files if bag is not None else mcap_files(path)
        storage = bag.storage if bag is not None else "mcap"
        types = dict(recording.topics)
    size = sum(f.stat().st_size for f in files)
    lines = [f"Files:             {', '.join(f.name for f in files)}",
             f"Bag size:          {_size(size)}",
             f"Storage id:        {storage}",
             f"Duration:          {_seconds(span[1] if span else 0)}s"]
    if span is not None:
        lines += [f"Start:             {_when(span[0])} ({_seconds(span[0])})",
                  f"End:               {_when(span[0] + span[1])} ({_seconds(span[0] + span[1])})"]
    lines.append(f"Messages:          {sum(counts.values())}")
    rows = [f"Topic: {topic} | Type: {types[topic]} | Count: {counts.get(topic, 0)} | Serialization Format: cdr"
            for topic in sorted(types)]
    lines.append("Topic information: " + "\n                   ".join(rows))
    return "\n".join(lines)


def _size(count: int) -> str:
    value = float(count)
    for unit in ("B", "KiB", "MiB", "GiB"):
        if value < 1024 or unit == "GiB":
            return f"{value:.1f} {unit}" if unit != "B" else f"{count} B"
        value /= 1024
    return f"{count} B"


def _seconds(stamp_ns: int) -> str:
    """Nanoseconds as seconds, every digit exact (a float loses the last ones of a stamp)."""
    return f"{stamp_ns // 1_000_000_000}.{stamp_ns % 1_000_000_000:09d}"


def _when(stamp_ns: int) -> str:
    import datetime

    moment = datetime.datetime.fromtimestamp(stamp_ns / 1e9, tz=datetime.UTC)
    return moment.strftime("%b %d %Y %H:%M:%S.") + f"{moment.microsecond // 1000:03d}"


def recorded_topics(path: Path) -> dict[str, str]:
    """Topic -> type of what ``path`` holds."""
    with Recording(path) as recording:
        return recording.topics


class Recording:
    """A bag to play or describe (``_bagfiles.Bag``: rosbag2 folders, MCAP, sqlite3, ROS 1). An MCAP file
    is checked first: where one is damaged, only its whole chunks are read, with what is damaged or
    missing named on stderr (never a traceback, nothing skipped uncounted)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        if not path.exists():
            raise InspectError(f"{path} does not exist")
        self.checks = [check(file) for file in mcap_files(path) if file.suffix == ".mcap"]
        self.bag: Bag | None = None
        self.topics: dict[str, str] = {}
        if all(found.whole for found in self.checks):
            self.bag = Bag(path)
            self.topics = {name: topic.type for name, topic in self.bag.topics.items()}
            return
        for found in self.checks:
            for line in found.lines():
                print(line, file=sys.stderr)
        skipped = sum(d.messages or 0 for found in self.checks for d in found.damaged)
        whole = sum(found.messages for found in self.checks)
        print(f"{path}: playing the {whole} messages of its whole chunks; {skipped} messages of damaged chunks "
              "skipped", file=sys.stderr)
        for file in mcap_files(path):
            for topic, msgtype, _time, _data in whole_messages(file):
                self.topics.setdefault(topic, msgtype)

    def messages(self, topics: set[str]) -> Iterator[tuple[str, int, bytes]]:
        """(topic, log time, CDR bytes) of the messages of ``topics``, in order."""
        if self.bag is not None:
            yield from self.bag.messages(topics)
            return
        for file in mcap_files(self.path):
            for topic, _msgtype, timestamp, data in whole_messages(file):
                if topic in topics:
                    yield topic, timestamp, data

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *_exc: object) -> None:
        if self.bag is not None:
            self.bag.close()


def play_launching(path: Path, project_file: Path, *, rate: float = 1.0, clock: bool = False, lockstep: bool = False,
                   topics: list[str] | None = None, start_offset: float = 0.0, remap: dict[str, str] | None = None,
                   qos_overrides: Path | None = None) -> int:
    """``hetros play --launch``: launch ``project_file`` without the nodes the recording stands in for (those
    that publish only recorded topics), play the recording into it, and stop it; the launch's exit code.
    ``qos_overrides`` sets the QoS of the topics it names in the launched project, as the player offers it."""
    from ...project import load_project
    from ...project import plan as make_plan
    from ..launcher._launcher import Launcher

    remap = dict(remap or {})
    fed = {remap.get(topic, topic) for topic in (topics or recorded_topics(path))}
    overrides = read_qos_overrides(qos_overrides) if qos_overrides is not None else {}
    project = load_project(project_file)
    nodes = project.model.nodes
    standing_in = {n for n, spec in nodes.items() if spec.publish and set(spec.types("publish")) <= fed}
    qos = {**project.model.topics, **{t: q for t, q in overrides.items() if t in fed}}
    project.model = project.model.model_copy(update={"nodes": {n: s for n, s in nodes.items() if n not in standing_in},
                                                     "topics": qos})
    project.replayed = frozenset(fed)
    if standing_in:
        print(f"the recording stands in for node(s) {', '.join(sorted(standing_in))}", file=sys.stderr)
    launcher = Launcher(make_plan(project))

    def player() -> None:
        ok, why = False, "the recording could not be played"
        try:
            deadline = time.monotonic() + 60
            while True:
                try:
                    looking = RunningLaunch.find(session=launcher.session)
                    if len(looking.stats()) == len(looking.processes()):
                        break
                except InspectError:
                    if time.monotonic() > deadline or launcher.stop.is_set():
                        raise
                time.sleep(0.1)
            counts = play(looking, path, rate=rate, clock=clock, lockstep=lockstep, topics=topics,
                          start_offset=start_offset, remap=remap)
            ok, why = True, f"the recording was played ({sum(counts.values())} messages)"
            print(describe_played(counts), flush=True)
        except Exception as exc:
            why = f"playing {path} failed: {exc}"
        finally:
            launcher.events.put({"event": "finished", "ok": ok, "why": why})
    threading.Thread(target=player, name="player", daemon=True).start()
    result = launcher.run()
    if result.exit_code:
        print(f"[play] graph stopped: {result.reason} (failed: {', '.join(result.failures) or '-'})", file=sys.stderr)
    return result.exit_code
