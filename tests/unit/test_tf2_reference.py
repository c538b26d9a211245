"""hetros's transform tree (``hetros.compat.tf2_py``) against Debian's tf2 (ROS 1's C++ BufferCore, the
reference peer), on the same messages: random trees of static and moving frames, looked up at stored
stamps, between them (interpolation), at time zero (the latest common time), beyond the data
(extrapolation, both ways), across unconnected trees, for unknown and malformed frame names, and through
a fixed frame. Every answer agrees within 1e-9 (a rotation up to its quaternion's sign), and every
error is the same exception with the same words."""

from __future__ import annotations

import json
import math
import random
import subprocess
from pathlib import Path
from typing import Any

import pytest

from hetros.compat.tf2_py import BufferCore, TransformException, _core
from hetros.msg import registry

REFERENCE = Path(__file__).resolve().parents[1] / "support" / "tf2_reference.py"
_HAS_TF2 = subprocess.run(["/usr/bin/python3", "-c", "import tf2_py, rospy"], capture_output=True,
                          check=False).returncode == 0 if Path("/usr/bin/python3").exists() else False

SECOND = 1_000_000_000


def _unit_quaternion(rng: random.Random) -> list[float]:
    q = [rng.gauss(0, 1) for _ in range(4)]
    norm = math.sqrt(sum(v * v for v in q))
    return [v / norm for v in q]


def _scenario(seed: int) -> dict[str, Any]:
    rng = random.Random(seed)
    frames = [f"f{i}" for i in range(12)]
    transforms = []
    for index, child in enumerate(frames[1:], 1):
        parent = frames[rng.randrange(index)] if index != 7 else "other_root"  # f7's subtree stands apart
        static = rng.random() < 0.3
        stamps = [0] if static else sorted(rng.sample(range(1, 40), rng.randint(1, 5)))
        for stamp in stamps:
            transforms.append({"parent": parent, "child": child, "static": static, "stamp": stamp * SECOND // 4,
                               "translation": [rng.uniform(-5, 5) for _ in range(3)],
                               "rotation": _unit_quaternion(rng)})
    names = [*frames, "other_root", "nowhere", "", "/f1"]
    queries: list[dict[str, Any]] = []
    for _ in range(120):
        time = rng.choice([0, rng.randrange(0, 45) * SECOND // 4, rng.randrange(0, 11 * SECOND)])
        query = {"target": rng.choice(names[:14]), "source": rng.choice(names[:14]), "time": time}
        if rng.random() < 0.2:
            query |= {"fixed": rng.choice(frames), "target_time": rng.choice([0, rng.randrange(0, 11 * SECOND)])}
        queries.append(query)
    queries += [{"target": "nowhere", "source": "f1", "time": 0}, {"target": "", "source": "f1", "time": 0},
                {"target": "f1", "source": "/f1", "time": 0}, {"target": "f0", "source": "f0", "time": 0}]
    return {"cache_s": 10, "transforms": transforms, "queries": queries}


def _reference(scenario: dict[str, Any]) -> list[dict[str, Any]]:
    done = subprocess.run(["/usr/bin/python3", str(REFERENCE)], input=json.dumps(scenario), capture_output=True,
                          text=True, check=True, timeout=60)
    answers: list[dict[str, Any]] = json.loads(done.stdout)
    return answers


def _ours(scenario: dict[str, Any]) -> list[dict[str, Any]]:
    make = registry().get("geometry_msgs/msg/TransformStamped")
    core = BufferCore(scenario["cache_s"])
    for item in scenario["transforms"]:
        message = make()
        message.header.frame_id, message.child_frame_id = item["parent"], item["child"]
        message.header.stamp.sec, message.header.stamp.nanosec = divmod(item["stamp"], SECOND)
        t, r = message.transform.translation, message.transform.rotation
        t.x, t.y, t.z = item["translation"]
        r.x, r.y, r.z, r.w = item["rotation"]
        (core.set_transform_static if item["static"] else core.set_transform)(message, "hetros")
    answers = []
    for query in scenario["queries"]:
        try:
            if "fixed" in query:
                pose, stamp = core.lookup_pose_full(query["target"], query["target_time"] / 1e9, query["source"],
                                                    query["time"] / 1e9, query["fixed"])
            else:
                pose, stamp = core.lookup_pose(query["target"], query["source"], _ns(query["time"]))
        except TransformException as exc:
            answers.append({"error": type(exc).__name__, "text": str(exc)})
            continue
        answers.append({"translation": list(pose[:3]), "rotation": list(pose[3:]), "stamp": stamp})
    return answers


class _Ns:
    """A time given as nanoseconds (what rclpy's Time holds)."""

    def __init__(self, ns: int) -> None:
        self.nanoseconds = ns


def _ns(ns: int) -> _Ns:
    return _Ns(ns)


@pytest.mark.skipif(not _HAS_TF2, reason="Debian's python3-tf2-ros is not installed")
@pytest.mark.parametrize("seed", range(6))
def test_lookups_agree_with_debians_tf2(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_core, "ros1_flavour", lambda: True)  # ROS 1's words, as the reference speaks
    scenario = _scenario(seed)
    reference, ours = _reference(scenario), _ours(scenario)
    errors = 0
    for query, want, got in zip(scenario["queries"], reference, ours, strict=True):
        if "error" in want:
            errors += 1
            assert got.get("error") == want["error"] and got.get("text") == want["text"], (query, want, got)
            continue
        assert "error" not in got, (query, want, got)
        assert got["stamp"] == want["stamp"], (query, want, got)
        assert max(abs(a - b) for a, b in zip(got["translation"], want["translation"], strict=True)) < 1e-9
        sign = 1.0 if sum(a * b for a, b in zip(got["rotation"], want["rotation"], strict=True)) >= 0 else -1.0
        assert max(abs(sign * a - b) for a, b in zip(got["rotation"], want["rotation"], strict=True)) < 1e-9, \
            (query, want, got)
    kinds = {want.get("error") for want in reference}
    assert errors and {"ExtrapolationException", "LookupException", "InvalidArgumentException"} <= kinds


@pytest.mark.parametrize("seed", range(3))
def test_the_compiled_walk_agrees_with_the_python_walk_to_the_bit(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """The compiled walk (``_ctf``) answers the lookups that succeed; the Python walk is the reference."""
    if _core._compiled_walk is None:
        pytest.skip("the compiled walk is not built here")
    scenario = _scenario(seed)
    compiled = _ours(scenario)
    monkeypatch.setattr(_core, "_compiled_walk", None)
    reference = _ours(scenario)
    assert compiled == reference
    assert sum("error" not in answer for answer in compiled) > 20
