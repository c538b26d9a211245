"""The transform tree: tf2's BufferCore, in Python.

Each frame keeps the transforms to its parent that it was given, for ``cache_time`` behind the newest
one (a static frame keeps one, valid at every time). A lookup walks from both frames up to their
common ancestor, taking each frame's transform at the asked time: the stored one at that stamp, or
the interpolation of the two around it (translation linear, rotation by tf2's slerp), or, at time
zero, the latest time every frame on the way has data for. Asking outside what a frame holds raises
tf2's ExtrapolationException, two frames of different trees its ConnectivityException, a frame no
one gave its LookupException, each with tf2's message.

A transform is ``(x, y, z, qx, qy, qz, qw)`` in plain floats: a lookup composes a handful of them,
where numpy's per-call cost would be most of the time.
"""

from __future__ import annotations

import bisect
import math
import sys
import threading
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from ..._errors import Error
from ..._log import get_logger

log = get_logger("tf2")


def _compiled() -> Any:
    """The compiled walk (``_ctf.walk``) where it is built and wanted (not ``HETROS_PURE_PYTHON``): it
    answers a lookup that succeeds, bit for bit as ``BufferCore._lookup``, and hands every other case
    to it (None)."""
    from ...msg import wanted

    if not wanted():
        return None
    try:
        from ._ctf import walk  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        return None
    return walk


_compiled_walk = _compiled()

Pose = tuple[float, float, float, float, float, float, float]
IDENTITY: Pose = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
DEFAULT_CACHE_NS = 10_000_000_000
MAX_DEPTH = 1000  # tf2's MAX_GRAPH_DEPTH: a longer walk is a loop


class TransformException(Error):
    """tf2's base exception."""


class LookupException(TransformException):
    """A frame nobody has given a transform for."""


class ConnectivityException(TransformException):
    """Two frames of different trees (or a loop)."""


class ExtrapolationException(TransformException):
    """A time outside what a frame on the way holds."""


class InvalidArgumentException(TransformException):
    """An empty frame name, one starting with '/', or a bad transform."""


class TimeoutException(TransformException):
    """A wait for a transform ended before it could be looked up."""


def to_ns(stamp: Any) -> int:
    """A time or duration of any ROS flavour as integer nanoseconds: rclpy's Time/Duration
    (``nanoseconds``), a builtin_interfaces message or rospy's Time/Duration (``sec``, ``nanosec``), or
    seconds as a number."""
    if stamp is None:
        return 0
    nanoseconds = getattr(stamp, "nanoseconds", None)
    if isinstance(nanoseconds, int):
        return nanoseconds
    if hasattr(stamp, "sec") and hasattr(stamp, "nanosec"):
        return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
    if hasattr(stamp, "secs") and hasattr(stamp, "nsecs"):
        return int(stamp.secs) * 1_000_000_000 + int(stamp.nsecs)
    if isinstance(stamp, int | float) and not isinstance(stamp, bool):
        return round(stamp * 1e9)
    raise InvalidArgumentException(f"a time must be a ROS time or a number of seconds, not {stamp!r}")


def ros1_flavour() -> bool:
    """Whether the code around speaks rospy (ROS 1's tf2 words its errors and times a little apart)."""
    return "rospy" in sys.modules and "rclpy" not in sys.modules


def _extrapolation(way: str, time: int, edge: int) -> ExtrapolationException:
    """tf2's words for a time beyond a frame's data: ROS 1's give the distance, ROS 2's do not."""
    bound = "latest" if way == "future" else "earliest"
    if ros1_flavour():
        return ExtrapolationException(
            f"Lookup would require extrapolation {seconds_text(abs(time - edge))}s into the {way}.  Requested time "
            f"{seconds_text(time)} but the {bound} data is at time {seconds_text(edge)}")
    return ExtrapolationException(f"Lookup would require extrapolation into the {way}.  Requested time "
                                  f"{time / 1e9:.6f} but the {bound} data is at time {edge / 1e9:.6f}")


def seconds_text(ns: int) -> str:
    """A time as tf2 prints it in its messages: seconds with nine decimals, every digit exact."""
    sign = "-" if ns < 0 else ""
    ns = abs(ns)
    return f"{sign}{ns // 1_000_000_000}.{ns % 1_000_000_000:09d}"


# -- transform arithmetic ------------------------------------------------------------------------

def compose(a: Pose, b: Pose) -> Pose:
    """a * b: b expressed in a's parent."""
    ax, ay, az, aqx, aqy, aqz, aqw = a
    bx, by, bz, bqx, bqy, bqz, bqw = b
    rx, ry, rz = rotate(aqx, aqy, aqz, aqw, bx, by, bz)
    return (ax + rx, ay + ry, az + rz,
            aqw * bqx + aqx * bqw + aqy * bqz - aqz * bqy,
            aqw * bqy - aqx * bqz + aqy * bqw + aqz * bqx,
            aqw * bqz + aqx * bqy - aqy * bqx + aqz * bqw,
            aqw * bqw - aqx * bqx - aqy * bqy - aqz * bqz)


def inverse(a: Pose) -> Pose:
    x, y, z, qx, qy, qz, qw = a
    rx, ry, rz = rotate(-qx, -qy, -qz, qw, x, y, z)
    return (-rx, -ry, -rz, -qx, -qy, -qz, qw)


def rotate(qx: float, qy: float, qz: float, qw: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    # v + 2w(q x v) + 2 q x (q x v), for a unit quaternion
    tx = 2.0 * (qy * z - qz * y)
    ty = 2.0 * (qz * x - qx * z)
    tz = 2.0 * (qx * y - qy * x)
    return (x + qw * tx + qy * tz - qz * ty,
            y + qw * ty + qz * tx - qx * tz,
            z + qw * tz + qx * ty - qy * tx)


def interpolate(a: Pose, b: Pose, ratio: float) -> Pose:
    """Between two transforms: translation linearly, rotation by tf2's slerp (the shorter way round)."""
    ax, ay, az, aqx, aqy, aqz, aqw = a
    bx, by, bz, bqx, bqy, bqz, bqw = b
    x, y, z = ax + (bx - ax) * ratio, ay + (by - ay) * ratio, az + (bz - az) * ratio
    magnitude = math.sqrt((aqx * aqx + aqy * aqy + aqz * aqz + aqw * aqw) * (bqx * bqx + bqy * bqy + bqz * bqz
                                                                             + bqw * bqw))
    product = (aqx * bqx + aqy * bqy + aqz * bqz + aqw * bqw) / magnitude
    if product >= 1.0 or product <= -1.0:
        return (x, y, z, aqx, aqy, aqz, aqw)
    sign = -1.0 if product < 0 else 1.0
    theta = math.acos(sign * product)
    d = 1.0 / math.sin(theta)
    s0 = math.sin((1.0 - ratio) * theta) * d
    s1 = math.sin(sign * ratio * theta) * d
    return (x, y, z, aqx * s0 + bqx * s1, aqy * s0 + bqy * s1, aqz * s0 + bqz * s1, aqw * s0 + bqw * s1)


def _chain(steps: list[tuple[str, tuple[str, Pose, Pose | None, float]]]) -> Pose:
    """The first frame of a walk in the last one's parent: its steps, interpolated and composed."""
    pose = IDENTITY
    for _frame, (_parent, before, after, ratio) in steps:
        pose = compose(before if after is None else interpolate(before, after, ratio), pose)
    return pose


# -- the tree -------------------------------------------------------------------------------------

@dataclass(slots=True)
class _Stored:
    stamp: int
    parent: str
    pose: Pose


class _Frame:
    """One frame's transforms to its parent over time (tf2's TimeCache), or its one static transform."""

    __slots__ = ("authority", "entries", "name", "stamps", "static")

    def __init__(self, name: str) -> None:
        self.name = name
        self.static: _Stored | None = None
        self.stamps: list[int] = []
        self.entries: list[_Stored] = []
        self.authority = ""

    def insert(self, stored: _Stored, cache_ns: int) -> bool:
        stamps = self.stamps
        if stamps and stored.stamp < stamps[-1] - cache_ns:
            return False  # older than the cache keeps: tf2's TF_OLD_DATA
        at = bisect.bisect_left(stamps, stored.stamp)
        if at < len(stamps) and stamps[at] == stored.stamp:
            return False  # tf2 ignores a repeated stamp (TF_REPEATED_DATA)
        stamps.insert(at, stored.stamp)
        self.entries.insert(at, stored)
        oldest = stamps[-1] - cache_ns
        if stamps[0] < oldest:
            cut = bisect.bisect_left(stamps, oldest)
            del stamps[:cut], self.entries[:cut]
        return True

    def latest(self) -> tuple[int, str]:
        """(newest stamp, its parent); a static frame's stamp is 0 (valid at any time)."""
        if self.static is not None:
            return 0, self.static.parent
        if not self.entries:
            return 0, ""
        newest = self.entries[-1]
        return newest.stamp, newest.parent

    def at(self, time: int) -> tuple[str, Pose]:
        """(parent, transform to it) at ``time`` (0: the newest)."""
        parent, before, after, ratio = self.bracket(time)
        return parent, before if after is None else interpolate(before, after, ratio)

    def bracket(self, time: int) -> tuple[str, Pose, Pose | None, float]:
        """(parent, the transform at or before ``time``, the one after it or None, the ratio between them):
        what ``at`` interpolates, found (and checked against the cache's span) without interpolating."""
        if self.static is not None:
            return self.static.parent, self.static.pose, None, 0.0
        entries = self.entries
        if not entries:
            raise LookupException(f"frame {self.name} holds no data")
        if time == 0:
            newest = entries[-1]
            return newest.parent, newest.pose, None, 0.0
        if len(entries) == 1:
            only = entries[0]
            if only.stamp == time:
                return only.parent, only.pose, None, 0.0
            shown = seconds_text if ros1_flavour() else (lambda ns: f"{ns / 1e9:.6f}")
            raise ExtrapolationException(f"Lookup would require extrapolation at time {shown(time)}, but only time "
                                         f"{shown(only.stamp)} is in the buffer")
        stamps = self.stamps
        if time > stamps[-1]:
            raise _extrapolation("future", time, stamps[-1])
        if time < stamps[0]:
            raise _extrapolation("past", time, stamps[0])
        at = bisect.bisect_left(stamps, time)
        after = entries[at]
        if after.stamp == time:
            return after.parent, after.pose, None, 0.0
        before = entries[at - 1]
        if before.parent != after.parent:
            return before.parent, before.pose, None, 0.0
        return before.parent, before.pose, after.pose, (time - before.stamp) / (after.stamp - before.stamp)


class BufferCore:
    """tf2's BufferCore: set transforms, look them up; safe to share between threads."""

    def __init__(self, cache_time: Any = None) -> None:
        self.cache_ns = DEFAULT_CACHE_NS if cache_time is None else to_ns(cache_time)
        self._frames: dict[str, _Frame] = {}
        self._lock = threading.RLock()
        self._listeners: list[Any] = []  # called after every accepted transform (waits)

    # -- input ------------------------------------------------------------------------------

    def set_transform(self, transform: Any, authority: str) -> None:
        """Add a transform that changes (ignored with tf2's error where tf2 ignores it: ``accept``)."""
        self.accept(transform, authority, static=False)

    def set_transform_static(self, transform: Any, authority: str) -> None:
        self.accept(transform, authority, static=True)

    def accept(self, transform: Any, authority: str, static: bool) -> bool:
        """Whether ``transform`` went into the tree."""
        parent = _strip(transform.header.frame_id)
        child = _strip(transform.child_frame_id)
        t, r = transform.transform.translation, transform.transform.rotation
        values = (float(t.x), float(t.y), float(t.z), float(r.x), float(r.y), float(r.z), float(r.w))
        problem = _refused(parent, child, values, authority)
        if problem:
            log.error(problem)
            return False
        norm = math.sqrt(values[3] ** 2 + values[4] ** 2 + values[5] ** 2 + values[6] ** 2)
        pose: Pose = (*values[:3], values[3] / norm, values[4] / norm, values[5] / norm, values[6] / norm)
        stored = _Stored(to_ns(transform.header.stamp), parent, pose)
        with self._lock:
            frame = self._frames.get(child)
            if frame is None:
                frame = self._frames[child] = _Frame(child)
            self._frames.setdefault(parent, _Frame(parent))
            if static:
                frame.static = stored
                accepted = True
            else:
                accepted = frame.insert(stored, self.cache_ns)
                if not accepted:
                    log.warning("TF_OLD_DATA or TF_REPEATED_DATA ignoring data for frame %s (parent %s) at time %s "
                                "according to authority %s", child, parent, seconds_text(stored.stamp), authority)
            if accepted:
                frame.authority = authority
            listeners = list(self._listeners)
        for listener in listeners:
            listener()
        return accepted

    def clear(self) -> None:
        with self._lock:
            for frame in self._frames.values():
                frame.stamps.clear()
                frame.entries.clear()

    def share_tree(self, tree: BufferCore) -> None:
        """Look up in ``tree`` from now on (one tree per process: ``tf2_ros.TransformListener``); what this
        core was told before is dropped, and its listeners hear ``tree``'s changes."""
        with tree._lock:
            tree._listeners.extend(self._listeners)
            self._frames, self._lock, self._listeners = tree._frames, tree._lock, tree._listeners

    def add_listener(self, listener: Any) -> None:
        with self._lock:
            self._listeners.append(listener)

    def remove_listener(self, listener: Any) -> None:
        with self._lock:
            if listener in self._listeners:
                self._listeners.remove(listener)

    # -- lookups ----------------------------------------------------------------------------

    def lookup_pose(self, target: str, source: str, time: Any) -> tuple[Pose, int]:
        """(the source frame's pose in the target frame, the time it is for) at ``time`` (0: the latest
        time both have data for)."""
        if target == source:  # tf2 answers the identity before it checks the names
            with self._lock:
                return IDENTITY, to_ns(time) or self._common_time(target, source)
        target, source = _checked(target, "target_frame"), _checked(source, "source_frame")
        with self._lock:
            self._exists(target, "target_frame")
            self._exists(source, "source_frame")
            return self._lookup(target, source, to_ns(time))

    def lookup_pose_full(self, target: str, target_time: Any, source: str, source_time: Any,
                         fixed: str) -> tuple[Pose, int]:
        """The source frame at ``source_time`` in the target frame at ``target_time``, through a frame fixed
        in the world between them."""
        target, source = _checked(target, "target_frame"), _checked(source, "source_frame")
        fixed = _checked(fixed, "fixed_frame")
        with self._lock:
            self._exists(target, "target_frame")
            self._exists(source, "source_frame")
            self._exists(fixed, "fixed_frame")
            source_in_fixed, _ = self._lookup(fixed, source, to_ns(source_time))
            fixed_in_target, stamp = self._lookup(target, fixed, to_ns(target_time))
            return compose(fixed_in_target, source_in_fixed), stamp

    def can_lookup(self, target: str, source: str, time: Any) -> tuple[bool, str]:
        try:
            self.lookup_pose(target, source, time)
        except TransformException as exc:
            return False, str(exc)
        return True, ""

    def can_lookup_full(self, target: str, target_time: Any, source: str, source_time: Any,
                        fixed: str) -> tuple[bool, str]:
        try:
            self.lookup_pose_full(target, target_time, source, source_time, fixed)
        except TransformException as exc:
            return False, str(exc)
        return True, ""

    def latest_common_time(self, target: str, source: str) -> int:
        target, source = _checked(target, "target_frame"), _checked(source, "source_frame")
        with self._lock:
            self._exists(target, "target_frame")
            self._exists(source, "source_frame")
            return self._common_time(target, source)

    def frames(self) -> list[str]:
        with self._lock:
            return sorted(name for name, frame in self._frames.items() if frame.static or frame.entries)

    def describe(self) -> list[dict[str, Any]]:
        """Per frame with a parent: name, parent, authority, its rate over the cache (Hz), its oldest and
        newest stamp (ns), and whether it is static: what ``all_frames_as_yaml`` and ``tf frames`` show."""
        with self._lock:
            rows = []
            for name, frame in self._frames.items():
                if frame.static is not None:
                    rows.append({"frame": name, "parent": frame.static.parent, "broadcaster": frame.authority,
                                 "rate": 10000.0, "oldest": 0, "latest": 0, "static": True})
                elif frame.entries:
                    oldest, newest = frame.stamps[0], frame.stamps[-1]
                    span = (newest - oldest) / 1e9
                    rate = len(frame.stamps) / span if span > 0 else 10000.0
                    rows.append({"frame": name, "parent": frame.entries[-1].parent, "broadcaster": frame.authority,
                                 "rate": rate, "oldest": oldest, "latest": newest, "static": False})
            return rows

    # -- the walk ---------------------------------------------------------------------------

    def _exists(self, frame: str, argument: str) -> None:
        known = self._frames.get(frame)
        if known is None or not (known.static or known.entries or self._is_parent(frame)):
            raise LookupException(f'"{frame}" passed to lookupTransform argument {argument} does not exist. ')

    def _is_parent(self, frame: str) -> bool:
        return any((f.static is not None and f.static.parent == frame) or (f.entries and f.entries[-1].parent == frame)
                   for f in self._frames.values())

    def _lookup(self, target: str, source: str, time: int) -> tuple[Pose, int]:
        """tf2's walk: from the source up to the top of its tree (or the target), then from the target up
        to that top (or the source). Both walks go past the common ancestor, as tf2's do, so a frame above
        it without data at ``time`` fails the lookup as it fails in tf2; a frame that cannot give its
        transform ends the source's walk (its error is told only if the target's walk does not meet it).
        Only the steps below the common ancestor are interpolated and composed: the rest cancels."""
        if time == 0:
            time = self._common_time(target, source)
        if target == source:
            return IDENTITY, time
        if _compiled_walk is not None:
            found = _compiled_walk(self._frames, target, source, time)
            if found is not None:
                return found, time
        where = f", when looking up transform from frame [{source}] to frame [{target}]"
        frames = self._frames
        up_source: list[tuple[str, tuple[str, Pose, Pose | None, float]]] = []
        frame, top, failure = source, source, ""
        for _ in range(MAX_DEPTH):
            known = frames.get(frame)
            if known is None or not (known.static or known.entries):
                top = frame
                break
            try:
                step = known.bracket(time)
            except ExtrapolationException as exc:
                top, failure = frame, str(exc)
                break
            if frame == target:
                return _chain(up_source), time
            up_source.append((frame, step))
            top, frame = frame, step[0]
        else:
            raise LookupException(f"The tf tree is invalid because it contains a loop.{where}")
        up_target: list[tuple[str, tuple[str, Pose, Pose | None, float]]] = []
        frame = target
        for _ in range(MAX_DEPTH):
            if frame == top:
                return self._meet(up_source, up_target), time
            known = frames.get(frame)
            if known is None or not (known.static or known.entries):
                break
            try:
                step = known.bracket(time)
            except ExtrapolationException as exc:
                raise ExtrapolationException(f"{exc}{where}") from None
            if frame == source:
                return inverse(_chain(up_target)), time
            up_target.append((frame, step))
            frame = step[0]
        else:
            raise LookupException(f"The tf tree is invalid because it contains a loop.{where}")
        if failure:
            raise ExtrapolationException(f"{failure}{where}")
        raise ConnectivityException(f"Could not find a connection between '{target}' and '{source}' because they "
                                    "are not part of the same tree.Tf has two or more unconnected trees.")

    @staticmethod
    def _meet(up_source: list[tuple[str, Any]], up_target: list[tuple[str, Any]]) -> Pose:
        """The source in the target, from both walks to a common top: composed up to the first frame the two
        share (above it the steps are the same on both sides)."""
        on_source = {frame: index for index, (frame, _step) in enumerate(up_source)}
        on_source[up_source[-1][1][0] if up_source else ""] = len(up_source)
        for index, (frame, _step) in enumerate(up_target):
            if frame in on_source:
                return compose(inverse(_chain(up_target[:index])), _chain(up_source[:on_source[frame]]))
        meet = on_source.get(up_target[-1][1][0] if up_target else "", len(up_source))
        return compose(inverse(_chain(up_target)), _chain(up_source[:meet]))

    def _climb(self, start: str) -> Iterator[tuple[str, int, str]]:
        """(frame, its newest stamp, its parent) from ``start`` up to the top of its tree: the walk of tf2's
        latest common time, which reads each frame's newest transform and interpolates nothing."""
        frame = start
        for _ in range(MAX_DEPTH):
            known = self._frames.get(frame)
            newest, parent = known.latest() if known is not None else (0, "")
            yield frame, newest, parent
            if not parent:
                return
            frame = parent

    def _common_time(self, target: str, source: str) -> int:
        """The latest time every frame between the two has data for (0 where all are static)."""
        if target == source:
            known = self._frames.get(target)
            return known.latest()[0] if known is not None else 0
        source_chain: dict[str, list[int]] = {}  # frame -> the non-zero newest stamps up to it
        stamps: list[int] = []
        for frame, newest, parent in self._climb(source):
            source_chain[frame] = list(stamps)
            if frame == target:
                return min(stamps, default=0)
            if not parent:
                break
            if newest:
                stamps.append(newest)
        target_stamps: list[int] = []
        for frame, newest, parent in self._climb(target):
            if frame in source_chain:
                return min(source_chain[frame] + target_stamps, default=0)
            if not parent:
                break
            if newest:
                target_stamps.append(newest)
        raise ConnectivityException(f"Could not find a connection between '{target}' and '{source}' because they "
                                    "are not part of the same tree.Tf has two or more unconnected trees.")


def _strip(frame: str) -> str:
    return str(frame).lstrip("/")


def _checked(frame: str, argument: str) -> str:
    frame = str(frame)
    if not frame:
        raise InvalidArgumentException(f"Invalid argument passed to lookupTransform argument {argument} in tf2 "
                                       "frame_ids cannot be empty")
    if frame.startswith("/"):
        raise InvalidArgumentException(f"Invalid argument \"{frame}\" passed to lookupTransform argument "
                                       f"{argument} in tf2 frame_ids cannot start with a '/' like: ")
    return frame


def _refused(parent: str, child: str, values: Iterable[float], authority: str) -> str:
    """Why tf2 would ignore this transform (its TF_* errors), or ''."""
    values = tuple(values)
    if child == parent:
        return (f"TF_SELF_TRANSFORM: Ignoring transform from authority \"{authority}\" with frame_id and "
                f"child_frame_id  \"{child}\" because they are the same")
    if not child:
        return (f"TF_NO_CHILD_FRAME_ID: Ignoring transform from authority \"{authority}\" because child_frame_id "
                "not set ")
    if not parent:
        return (f"TF_NO_FRAME_ID: Ignoring transform with child_frame_id \"{child}\"  from authority \"{authority}\" "
                "because frame_id not set")
    if any(math.isnan(v) or math.isinf(v) for v in values):
        return (f"TF_NAN_INPUT: Ignoring transform for child_frame_id \"{child}\" from authority \"{authority}\" "
                "because of a nan value in the transform")
    if abs(sum(v * v for v in values[3:]) - 1.0) > 10e-6:
        return (f"TF_DENORMALIZED_QUATERNION: Ignoring transform for child_frame_id \"{child}\" from authority "
                f"\"{authority}\" because of an invalid quaternion in the transform")
    return ""
