"""Every file a user or another account can name, fed what an unlucky user or an attacker would: each
reader either reads it or raises a hetros error naming it, within seconds, never a traceback.

The surfaces: project files, ROS 1 and ROS 2 launch files (with includes of each other), parameter
files, launch records, plans, advise profiles and calibrations, rosbag2 QoS override files, ROS-lite
maps, ReconROS build files, `hetros init` sources and bags. Each gets ``CASES`` generated inputs
(2,000; ``HETROS_SOAK=1``: 10,000): mutations of a valid file's bytes, and structured nonsense
(nesting, aliases, huge numbers, control characters). A FIFO, /dev/zero and a folder are refused by
name by every one of them, without blocking.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hetros import Error
from hetros.advise._calibrate import Calibration
from hetros.advise._profile import Profile
from hetros.launch.observe._bag import read_qos_overrides
from hetros.launch.observe._bagfiles import Bag
from hetros.plan import Plan
from hetros.project import (
    check,
    import_launch,
    import_reconros,
    import_roslite,
    load_project,
    plan_file,
    ros_template,
    template_from_sources,
)
from hetros.project._expand import parameters_from_files

SOAK = os.environ.get("HETROS_SOAK") == "1"
CASES = int(os.environ.get("HETROS_HOSTILE_CASES", 10_000 if SOAK else 2_000))
PER_CASE_SECONDS = 10.0
SETTINGS = settings(max_examples=CASES, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))
ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "talker_listener" / "project.yaml"


def _seed_plan() -> str:
    return plan_file(EXAMPLE).to_json()


SEEDS: dict[str, bytes] = {
    "project": EXAMPLE.read_bytes(),
    "ros1_launch": b'<launch>\n  <arg name="rate" default="10"/>\n  <include file="inner.launch">\n'
                   b'    <arg name="x" value="$(arg rate)"/>\n  </include>\n  <group ns="r2">\n'
                   b'    <param name="global_example" value="3"/>\n  </group>\n</launch>\n',
    "ros2_launch_xml": b'<launch>\n  <arg name="ns" default="a"/>\n  <group>\n    <push-ros-namespace namespace='
                       b'"$(var ns)"/>\n    <include file="inner.launch.yaml"/>\n  </group>\n</launch>\n',
    "ros2_launch_yaml": b'launch:\n- arg: {name: who, default: x}\n- include: {file: "inner.launch.xml"}\n'
                        b'- group:\n  - push-ros-namespace: {namespace: "$(var who)"}\n',
    "parameters": b"/**:\n  ros__parameters:\n    rate: 10.0\n    names: [a, b]\n    nested: {deep: {x: 1}}\n",
    "plan": b"",  # filled from the example's plan at collection time
    "profile": json.dumps({"format": 1, "machine": {}, "graph": "x", "nodes": {"a": {
        "handling": {"/x": {"count": 1, "p50_ms": 1.0, "p99_ms": 2.0, "cpu_ms": 0.5}}}},
        "topics": {"/x": {"rate_hz": 10.0, "size": 4}}, "processes": {"p": 0.1}}).encode(),
    "calibration": json.dumps({"machine": {"cpu": "x"}, "table": {"shm": [[4, 10.0, 20.0]]},
                               "wake_ms": {"thread": 0.1}}).encode(),
    "qos_overrides": b"/chatter:\n  reliability: best_effort\n  history: keep_last\n  depth: 5\n"
                     b"  deadline: {sec: 1, nsec: 0}\n",
    "roslite": b"nodes:\n- {name: a, cluster: 1, publish: [x], publish_type: [std_msgs/msg/String]}\n",
    "reconros": b"[General]\nName = demo\n[HwThread@sobel]\nSlots = 0\nrossub = /image,sensor_msgs/msg/Image\n",
    "python": b"import rclpy\nfrom rclpy.node import Node\nfrom std_msgs.msg import String\n\n\nclass T(Node):\n"
              b"    def __init__(self):\n        super().__init__('t')\n"
              b"        self.create_publisher(String, 'chatter', 10)\n\n\ndef main():\n    rclpy.init()\n",
    "bag": (ROOT / "tests" / "data" / "rosbag2" / "mcap" / "talker" / "talker.mcap").read_bytes()[:4096],
}


def _mutated(seed: bytes) -> st.SearchStrategy[bytes]:
    """``seed`` with a few bytes flipped, cut, repeated or replaced by hostile snippets."""
    hostile = st.sampled_from([b"\x00", b"\x1b[2J", b"\xff\xfe", b"&a", b"*a", b"[" * 200, b"{" * 200,
                               b"<group>" * 120, b"$(", b"$(eval 1+(2))", b"$()", b"$(file-content /dev/zero)",
                               b"1e999", b"-1", b"nan", b"!!python/object:os.system", b"\n  " * 40,
                               b"<!DOCTYPE x [<!ENTITY a 'aaaa'>]>", b"%", b"\t\r\n", b"\xc3\x28"])

    @st.composite
    def build(draw: Any) -> bytes:
        data = bytearray(seed)
        for _ in range(draw(st.integers(1, 6))):
            where = draw(st.integers(0, max(len(data), 1)))
            action = draw(st.integers(0, 3))
            if action == 0 and data:
                data[min(where, len(data) - 1)] = draw(st.integers(0, 255))
            elif action == 1:
                del data[where:where + draw(st.integers(1, 40))]
            elif action == 2:
                data[where:where] = draw(hostile)
            else:
                data[where:where] = data[where:where + draw(st.integers(1, 60))] * draw(st.integers(2, 30))
        return bytes(data)
    return build()


json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-2**70, 2**70), st.floats(), st.text(max_size=20)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=10), inner, max_size=4)),
    max_leaves=20)


def _inputs(kind: str) -> st.SearchStrategy[bytes]:
    seed = SEEDS[kind] or _seed_plan().encode()
    structured = json_values.map(lambda v: json.dumps(v).encode())
    return st.one_of(_mutated(seed), structured, st.binary(max_size=300))


def _within_time(read: Callable[[], object], what: str) -> None:
    """``read()`` ends within ``PER_CASE_SECONDS`` with a result or a hetros error, nothing else."""
    outcome: list[BaseException | None] = []

    def run() -> None:
        try:
            read()
            outcome.append(None)
        except Error:
            outcome.append(None)
        except BaseException as exc:  # the defect this suite exists to find
            outcome.append(exc)
    worker = threading.Thread(target=run, daemon=True)
    start = time.monotonic()
    worker.start()
    worker.join(PER_CASE_SECONDS)
    assert not worker.is_alive(), f"{what}: still reading after {PER_CASE_SECONDS} s"
    assert outcome and outcome[0] is None, f"{what}: {outcome[0]!r} where a hetros error belongs"
    assert time.monotonic() - start < PER_CASE_SECONDS


def _project(path: Path) -> None:
    loaded = load_project(path)
    check(loaded)


READERS: dict[str, tuple[str, Callable[[Path, Path], object]]] = {
    "project": ("project.yaml", lambda path, tmp: _project(path)),
    "ros1_launch": ("main.launch", lambda path, tmp: import_launch(path, False, [tmp], tmp)),
    "ros2_launch_xml": ("main.launch.xml", lambda path, tmp: import_launch(path, True, [tmp], tmp)),
    "ros2_launch_yaml": ("main.launch.yaml", lambda path, tmp: import_launch(path, True, [tmp], tmp)),
    "parameters": ("params.yaml", lambda path, tmp: parameters_from_files([path], "/ns/node")),
    "plan": ("plan.json", lambda path, tmp: Plan.from_json(path.read_text(errors="replace"), str(path))),
    "profile": ("profile.json", lambda path, tmp: Profile.load(path)),
    "calibration": ("calibration.json", lambda path, tmp: Calibration.load(path)),
    "qos_overrides": ("overrides.yaml", lambda path, tmp: read_qos_overrides(path)),
    "roslite": ("graph.map", lambda path, tmp: import_roslite(path)),
    "reconros": ("build.cfg", lambda path, tmp: import_reconros(path)),
    "python": ("node.py", lambda path, tmp: (ros_template([path], "x", tmp),
                                             template_from_sources([path], tmp, "x", tmp))),
    "bag": ("x.mcap", lambda path, tmp: list(Bag(path).messages(None))),
}
# the files the launch files include: each of the three kinds includes the others, and itself
INCLUDED = {"inner.launch": SEEDS["ros1_launch"].replace(b"inner.launch", b"main.launch"),
            "inner.launch.xml": SEEDS["ros2_launch_xml"].replace(b"inner.launch.yaml", b"main.launch.yaml"),
            "inner.launch.yaml": SEEDS["ros2_launch_yaml"].replace(b"inner.launch.xml", b"main.launch.xml")}


@pytest.mark.timeout(1800)  # thousands of cases: minutes on a loaded machine
@pytest.mark.parametrize("kind", sorted(READERS))
def test_a_hostile_file_is_read_or_refused_by_name(kind: str, tmp_path_factory: pytest.TempPathFactory) -> None:
    folder = tmp_path_factory.mktemp(kind)
    for name, text in INCLUDED.items():
        (folder / name).write_bytes(text)
    (folder / "fuzz_nodes.py").write_text("def talker(node):\n    pass\n")
    name, read = READERS[kind]
    path = folder / name

    @SETTINGS
    @given(_inputs(kind))
    def case(data: bytes) -> None:
        path.write_bytes(data)
        _within_time(lambda: read(path, folder), f"{kind} {data[:80]!r}")
    case()


@pytest.mark.parametrize("kind", sorted(READERS))
def test_what_is_not_a_file_is_refused_by_name_without_blocking(kind: str, tmp_path: Path) -> None:
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    folder = tmp_path / "folder"
    folder.mkdir()
    _name, read = READERS[kind]
    for path, words in ((fifo, "FIFO"), (Path("/dev/zero"), "character device"), (folder, "folder")):
        if kind == "plan":
            continue  # a plan is read by the caller (RunningLaunch, through _files); its text is what is checked
        outcome: list[BaseException] = []
        worker = threading.Thread(target=lambda p=path, o=outcome: _catch(lambda: read(p, tmp_path), o), daemon=True)
        worker.start()
        worker.join(PER_CASE_SECONDS)
        assert not worker.is_alive(), f"{kind}: reading {path} blocked"
        assert outcome and isinstance(outcome[0], Error), f"{kind} {path}: {outcome!r}"
        assert words in str(outcome[0]) or "not a bag" in str(outcome[0]) or "does not exist" in str(outcome[0]), \
            f"{kind} {path}: {outcome[0]}"


def _catch(read: Callable[[], object], outcome: list[BaseException]) -> None:
    try:
        read()
    except BaseException as exc:
        outcome.append(exc)
