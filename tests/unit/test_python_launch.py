"""Python launch files (ROS 2's ``generate_launch_description()``) into projects: the actions,
substitutions, conditions, scopes and includes launch files use, evaluated as ``ros2 launch`` does, and
what hetros cannot express refused at its line."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from hetros import ProjectError
from hetros.project import import_launch
from hetros.project._launch_import import lifecycle_state_after, ros2_parameter_file

CASES = Path(__file__).resolve().parents[1] / "cases" / "launch_py"
TWINS = Path(__file__).resolve().parents[1] / "data" / "cpp_twins"


def _imported(file: Path, tmp_path: Path, args: dict[str, str] | None = None) -> tuple[dict[str, Any], list[str]]:
    return import_launch(file, True, [TWINS], tmp_path, args)


def test_a_launch_file_becomes_the_graph_it_declares(tmp_path: Path) -> None:
    project, notes = _imported(CASES / "main.launch.py", tmp_path)
    nodes = project["nodes"]
    # conditions: UnlessCondition(true) skips "skipped"; the PythonExpression and LaunchConfigurationEquals hold
    assert list(nodes) == ["my_talker", "grouped", "outside", "included", "from_xml", "extra0", "extra1", "equal"]
    talker = nodes["my_talker"]
    assert talker["name"] == "my_talker"  # name=[LaunchConfiguration('prefix'), 'talker']
    assert talker["run"] == "demo_nodes_py.topics.talker:main"
    # dict values (a substitution read as YAML), nested dicts dotted, then the file's /** and my_talker entries
    # (later wins), then the --ros-args -p; the file's `other:` entry is not this node's
    assert talker["parameters"] == {"rate": 5.0, "nested.gain": 2.5, "nested.name": "x", "everyone": 1,
                                    "mine": True, "from_cli": 7}
    assert talker["remap"] == {"chatter": "speech", "extra": "other"}
    assert talker["args"] == ["--flag"]  # the --ros-args section is applied, not passed on
    assert talker["required"] is True  # OnProcessExit(talker) -> Shutdown
    assert talker["env"] == {"HETROS_CASE": "yes"}
    grouped = nodes["grouped"]  # PushRosNamespace, SetRemap, SetParameter inside a scoped group
    assert grouped["namespace"] == "/robot"
    assert grouped["remap"] == {"chatter": "/speech"}
    assert grouped["parameters"]["use_sim_time"] is True
    assert grouped["parameters"]["share"] == str(TWINS / "demo_nodes_cpp")
    assert "namespace" not in nodes["outside"]  # the group's scope ended with it
    assert "remap" not in nodes["outside"]
    assert nodes["included"]["namespace"] == "/sub"  # a Python include with launch_arguments
    assert nodes["from_xml"]["name"] == "from_xml"  # an XML include, its <arg> given by the Python file
    assert nodes["extra1"]["namespace"] == "/extra"  # OpaqueFunction(args=[1]) with listeners=1 -> two nodes
    assert any("TimerAction(period=2.0)" in note for note in notes)
    assert any(note.endswith("later") for note in notes)  # LogInfo


def test_launch_arguments_from_the_command_line(tmp_path: Path) -> None:
    project, _ = _imported(CASES / "main.launch.py", tmp_path,
                           {"prefix": "other_", "with_group": "false", "listeners": "0"})
    nodes = project["nodes"]
    assert "other_talker" in nodes
    assert nodes["other_talker"]["parameters"]["rate"] == 2.0  # the file's my_talker entry is not this node's
    assert "skipped" in nodes and "grouped" not in nodes and "outside" not in nodes and "equal" not in nodes
    assert sorted(k for k in nodes if k.startswith("extra")) == ["extra0"]


@pytest.mark.parametrize(("case", "line", "words"), [
    ("command", 9, "Command(...) runs a program"),
    ("program", 7, "ExecuteProcess of 'rviz2'"),
    ("missing_argument", 7, "launch argument 'robot' has no value"),
    ("raises", 6, "KeyError"),
    ("no_function", 1, "defines generate_launch_description()"),
    ("choices", 7, "must be one of ['slow', 'normal'], not 'fast'"),
])
def test_what_hetros_cannot_express_is_refused_at_its_line(case: str, line: int, words: str,
                                                           tmp_path: Path) -> None:
    file = CASES / "refused" / f"{case}.launch.py"
    with pytest.raises(ProjectError) as refused:
        _imported(file, tmp_path)
    assert str(refused.value).startswith(f"{file}:{line}: "), refused.value
    assert words in str(refused.value)


def test_a_ros2_parameter_file_gives_a_node_its_own_entries(tmp_path: Path) -> None:
    file = tmp_path / "params.yaml"
    file.write_text("/**:\n  ros__parameters: {a: 1, b: 1}\n"
                    "/robot/*:\n  ros__parameters: {b: 2}\n"
                    "camera:\n  ros__parameters: {c: {d: 3}}\n"
                    "/other/camera:\n  ros__parameters: {e: 4}\n")
    assert ros2_parameter_file(file, "/robot/camera", "here") == {"a": 1, "b": 2, "c.d": 3}
    assert ros2_parameter_file(file, "/other/camera", "here") == {"a": 1, "b": 1, "c.d": 3, "e": 4}
    assert ros2_parameter_file(file, "/camera", "here") == {"a": 1, "b": 1, "c.d": 3}
    file.write_text("camera: {not_parameters: 1}\n")
    with pytest.raises(ProjectError, match=r"^here: .*ros__parameters"):
        ros2_parameter_file(file, "/camera", "here")


def test_lifecycle_transitions_a_launch_asks() -> None:
    assert lifecycle_state_after("unconfigured", 1, "here") == "inactive"
    assert lifecycle_state_after("inactive", 3, "here") == "active"
    with pytest.raises(ProjectError, match="starts from inactive, but the node is unconfigured"):
        lifecycle_state_after("unconfigured", 3, "here")
