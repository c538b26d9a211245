"""tf2 in running graphs, with code nobody wrote for hetros: geometry2's examples_tf2_py package (static
and dynamic broadcasters, a frame dumper, and three ways of waiting for a transform), imported by
`hetros init` and launched unchanged with every node in a process of its own; and tf2_ros_py's own
listener-and-broadcaster test, run as a node of a launch."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import yaml

from tests.support.cli import hetros_in, looked_at, private_env

DATA = Path(__file__).resolve().parents[1] / "data"


def test_geometry2s_tf2_examples_run_unchanged_across_processes(tmp_path: Path) -> None:
    """Also: `hetros tf echo` and `tf frames` on the running graph, the static frames (sent once, before
    they looked) included."""
    done = hetros_in("init", str(DATA / "examples_tf2_py"), "-o", str(tmp_path / "project.yaml"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    project = yaml.safe_load((tmp_path / "project.yaml").read_text())
    nodes = project["nodes"]
    assert nodes["example_static_frame_publisher"]["publish"] == {"/tf_static": "tf2_msgs/msg/TFMessage"}
    assert nodes["example_frame_dumper"]["subscribe"] == {"/tf": "tf2_msgs/msg/TFMessage",
                                                          "/tf_static": "tf2_msgs/msg/TFMessage"}
    assert project["topics"]["/tf_static"]["durability"] == "transient_local"
    assert len(set(node["target"] for node in nodes.values())) == len(nodes) == 6
    with subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration",
                           "8"], cwd=tmp_path, env=private_env(tmp_path), stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True) as launch:
        try:
            echoed = looked_at(tmp_path, "tf", "echo", "base_link", "sonar_0", "--once", "--duration", "5")
            frames = looked_at(tmp_path, "tf", "frames", "--duration", "2", "-o", str(tmp_path / "frames"))
            stdout, stderr = launch.communicate(timeout=120)
        finally:
            launch.kill()
    assert launch.returncode == 0, stderr
    # platform is 0.1 over base_link, sonar_0 0.05 m at 45 degrees on it, turned by its quaternion
    assert "- Translation: [0.035, 0.035, 0.100]" in echoed and \
        "- Rotation: in Quaternion (xyzw) [0.000, 0.000, -0.487, -0.873]" in echoed, echoed
    assert "  sonar_2  (static, broadcaster example_static_frame_publisher)" in frames, frames
    assert re.search(r"  port_wheel  \(\d+\.\d\d Hz, latest \d+\.\d+, broadcaster dynamic_broadcaster\)", frames)
    assert (tmp_path / "frames.svg").read_text().lstrip().startswith(("<?xml", "<svg"))
    out = stdout + stderr
    for node in ("example_waits_for_transform", "example_blocking_waits_for_transform"):
        assert re.search(rf"\[{node}\]: Got transform$", out, re.MULTILINE), out
    assert re.search(r"\[example_async_waits_for_transform\]: Got TransformStamped\(.*child_frame_id='sonar_2'", out)
    dumped = [yaml.safe_load(block) for block in re.findall(r"((?:^\w+: \n(?:  .*\n)+)+)", out, re.MULTILINE)]
    last = dumped[-1]
    assert {frame: entry["parent"] for frame, entry in last.items()} == {
        "platform": "base_link", "camera": "platform", "sonar_0": "platform", "sonar_1": "platform",
        "sonar_2": "platform", "port_wheel": "base_link", "starboard_wheel": "base_link"}
    # a moving frame: several stamps over time (its rate is a timing, which a busy machine moves)
    assert last["port_wheel"]["buffer_length"] > 0 and last["port_wheel"]["rate"] != 10000.0
    assert last["camera"]["rate"] == 10000.0  # tf2's figure for a static frame


def test_tf2_ros_pys_listener_and_broadcaster_test_passes_as_a_node(tmp_path: Path) -> None:
    (tmp_path / "runner.py").write_text(
        "import sys\n\nimport pytest\n\n\ndef main():\n"
        "    sys.exit(int(pytest.main(['-q', '-p', 'no:cacheprovider', sys.argv[1]])))\n")
    tf_topics = {"/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage"}
    project = {"name": "tf2test", "nodes": {"test_broadcaster_listener": {
        "run": "runner:main", "args": [str(DATA / "upstream_tf2" / "test_listener_and_broadcaster.py")],
        "publish": tf_topics, "subscribe": tf_topics}}}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project))
    done = hetros_in("launch", str(tmp_path / "project.yaml"), cwd=tmp_path, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "3 passed" in done.stdout + done.stderr
