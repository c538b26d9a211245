"""``hetros tf echo SOURCE TARGET`` and ``hetros tf frames``: a running launch's transform tree, as tf2_ros's
``tf2_echo`` and tf2_tools' ``view_frames`` show it. Both read /tf and /tf_static through the launch's taps
(a transient_local /tf_static's last messages come first, as to a late subscriber) into a tree of their
own (hetros.compat.tf2_py)."""

from __future__ import annotations

import argparse
import math
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

from .._errors import InspectError
from ..compat.tf2_py import BufferCore, TransformException
from ..launch import RunningLaunch
from ._args import hertz, seconds

TF_TOPICS = ("/tf", "/tf_static")


def _fed(launch: RunningLaunch, duration: float | None) -> Any:
    """Yield (tree, seconds since start) each time a message came in, and every half second."""
    topics = [topic for topic in TF_TOPICS if topic in launch.plan.channels]
    if not topics:
        raise InspectError("the launch has no /tf or /tf_static: no node broadcasts transforms")
    core = BufferCore(10.0)
    start = time.monotonic()
    plan = launch.plan
    for topic, event in launch.tap_many(topics, data=True):
        if event is not None and event.data is not None:
            message: Any = launch.decode("tf2_msgs/msg/TFMessage", event.data)
            # the broadcaster: the node(s) of the tapped process that publish the topic
            nodes = [n for n in plan.channels[topic].publishers if n in plan.nodes and
                     plan.process_of(n) == event.process]
            for transform in message.transforms:
                core.accept(transform, ", ".join(nodes) or event.process or "unknown", static=topic == "/tf_static")
        elapsed = time.monotonic() - start
        yield core, elapsed
        if duration is not None and elapsed >= duration:
            return


def _rpy(qx: float, qy: float, qz: float, qw: float) -> tuple[float, float, float]:
    roll = math.atan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (qw * qy - qz * qx))))
    yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
    return roll, pitch, yaw


def describe_transform(pose: tuple[float, ...], stamp_ns: int) -> str:
    """One transform as tf2_echo prints it."""
    x, y, z, qx, qy, qz, qw = pose
    rpy = _rpy(qx, qy, qz, qw)
    matrix = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw), x],
              [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw), y],
              [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy), z],
              [0.0, 0.0, 0.0, 1.0]]

    def row(values: Any) -> str:
        return ", ".join(f"{v:.3f}" for v in values)
    lines = [f"At time {stamp_ns // 1_000_000_000}.{stamp_ns % 1_000_000_000:09d}",
             f"- Translation: [{row((x, y, z))}]",
             f"- Rotation: in Quaternion (xyzw) [{row((qx, qy, qz, qw))}]",
             f"- Rotation: in RPY (radian) [{row(rpy)}]",
             f"- Rotation: in RPY (degree) [{row(math.degrees(a) for a in rpy)}]",
             "- Matrix:"]
    lines += ["  " + " ".join(f"{v:6.3f}" for v in values) for values in matrix]
    return "\n".join(lines)


def cmd_tf_echo(args: argparse.Namespace) -> int:
    """The target frame's pose in the source frame, at the latest common time, every 1/rate s."""
    if not args.rate > 0:
        raise InspectError(f"--rate must be a positive number of echoes a second, not {args.rate!r}")
    launch = RunningLaunch.find(args.session, args.project)
    shown, next_due = 0, 0.0
    for core, elapsed in _fed(launch, args.duration):
        if elapsed < next_due:
            continue
        next_due = elapsed + 1.0 / args.rate
        try:
            pose, stamp = core.lookup_pose(args.source, args.target, 0)
        except TransformException as exc:
            if elapsed > 1.0:
                print(f"Waiting for transform {args.source} ->  {args.target}: {exc}", flush=True)
            continue
        print(describe_transform(pose, stamp), flush=True)
        shown += 1
        if args.once:
            return 0
    return 0 if shown else 1


def frames_dot(rows: list[dict[str, Any]]) -> str:
    lines = ["digraph tf {", '  rankdir=TB; node [shape=ellipse, fontname="sans"];']
    for row in rows:
        latest = "static" if row["static"] else f"latest {row['latest'] / 1e9:.3f}"
        rate = "static" if row["static"] else f"{row['rate']:.2f} Hz"
        lines.append(f'  "{row["parent"]}" -> "{row["frame"]}" [label="Broadcaster: {row["broadcaster"]}\\n'
                     f'Rate: {rate}\\n{latest}", fontsize=10];')
    lines.append("}")
    return "\n".join(lines) + "\n"


def frames_text(rows: list[dict[str, Any]]) -> str:
    """The tree, each frame under its parent, with its broadcaster, rate and latest stamp."""
    children: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for row in rows:
        children[row["parent"]].append(row)
    roots = sorted({row["parent"] for row in rows} - {row["frame"] for row in rows})
    lines: list[str] = []

    def walk(frame: str, depth: int) -> None:
        for row in sorted(children.get(frame, []), key=lambda r: r["frame"]):
            what = "static" if row["static"] else f"{row['rate']:.2f} Hz, latest {row['latest'] / 1e9:.3f}"
            lines.append(f"{'  ' * depth}{row['frame']}  ({what}, broadcaster {row['broadcaster']})")
            walk(row["frame"], depth + 1)
    for root in roots:
        lines.append(root)
        walk(root, 1)
    return "\n".join(lines)


def cmd_tf_frames(args: argparse.Namespace) -> int:
    """Listen for ``--duration`` seconds, then print the tree and write it as SVG (tf2_tools' view_frames)."""
    if not args.duration > 0:
        raise InspectError(f"--duration must be positive seconds, not {args.duration!r}")
    launch = RunningLaunch.find(args.session, args.project)
    print(f"Listening to tf data for {args.duration:g} seconds...", flush=True)
    rows: list[dict[str, Any]] = []
    for tree, _elapsed in _fed(launch, args.duration):
        rows = tree.describe()
    if not rows:
        raise InspectError(f"no transform on /tf or /tf_static in {args.duration:g} s")
    print(frames_text(rows))
    from ..project import render_svg

    written = render_svg(frames_dot(rows), Path(args.output))
    print(f"wrote {', '.join(str(path) for path in written)}")
    return 0


def add_commands(sub: Any, which: Any) -> None:
    tf = sub.add_parser("tf", help="a running launch's transform tree (tf2_echo, view_frames)")
    verbs = tf.add_subparsers(dest="tf_command", required=True)
    p = verbs.add_parser("echo", help="the target frame's pose in the source frame (tf2_echo)")
    p.add_argument("source")
    p.add_argument("target")
    p.add_argument("--rate", type=hertz, default=1.0, help="echoes a second (default 1)")
    p.add_argument("--duration", type=seconds, help="stop after this many seconds")
    p.add_argument("--once", action="store_true", help="echo one transform and stop")
    p.set_defaults(func=cmd_tf_echo)
    which(p)
    p = verbs.add_parser("frames", help="the tree as text and SVG, each frame's broadcaster, rate and latest stamp")
    p.add_argument("--duration", type=seconds, default=5.0, help="seconds to listen (default 5)")
    p.add_argument("-o", "--output", default="frames", help="the SVG's path without suffix (default frames)")
    p.set_defaults(func=cmd_tf_frames)
    which(p)
