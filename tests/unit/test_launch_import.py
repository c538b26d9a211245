"""Launch-file import edge cases, as ROS resolves them: ``$(file-content)``, a YAML group written as a list
of actions, and a relative ``--package-path`` whose ``$(find)`` must still name the package."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from hetros.project._launch_import import import_launch

TESTS = Path(__file__).resolve().parents[1]
ROS2_PACKAGES = TESTS / "data" / "ros2_examples" / "rclpy"
ROS1_PACKAGES = TESTS / "data" / "ros_tutorials"


def test_file_content_is_the_files_text(tmp_path: Path) -> None:
    (tmp_path / "ns.txt").write_text("robot_7")
    launch = tmp_path / "demo.launch.xml"
    launch.write_text('<launch>\n  <group>\n    <push-ros-namespace namespace="$(file-content ns.txt)"/>\n'
                      '    <node pkg="examples_rclpy_executors" exec="talker" name="talker"/>\n  </group>\n</launch>\n')
    project, _ = import_launch(launch, True, [ROS2_PACKAGES], tmp_path)
    assert project["nodes"]["talker"]["namespace"] == "/robot_7"
    launch.write_text('<launch>\n  <node pkg="examples_rclpy_executors" exec="talker" name="$(file-content no.txt)"/>'
                      "\n</launch>\n")
    with pytest.raises(Exception, match=r"demo.launch.xml:2: \$\(file-content no.txt\): No such file"):
        import_launch(launch, True, [ROS2_PACKAGES], tmp_path)


def test_a_yaml_group_may_be_a_list_of_actions(tmp_path: Path) -> None:
    launch = tmp_path / "demo.launch.yaml"
    launch.write_text("launch:\n- group:\n  - push-ros-namespace: {namespace: grouped}\n"
                      "  - node: {pkg: examples_rclpy_executors, exec: talker, name: talker}\n"
                      "- node: {pkg: examples_rclpy_executors, exec: listener, name: listener}\n")
    project, _ = import_launch(launch, True, [ROS2_PACKAGES], tmp_path)
    assert project["nodes"]["talker"]["namespace"] == "/grouped"
    assert project["nodes"]["listener"].get("namespace", "") in ("", "/")  # the group's scope ended


def test_a_relative_package_path_finds_the_package_from_anywhere(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    launch = tmp_path / "demo.launch.xml"
    launch.write_text('<launch>\n  <node pkg="examples_rclpy_executors" exec="talker" name="talker">\n'
                      '    <param name="share" value="$(find-pkg-share examples_rclpy_executors)"/>\n'
                      "  </node>\n</launch>\n")
    monkeypatch.chdir(TESTS)
    relative = Path(os.path.relpath(ROS2_PACKAGES, TESTS))
    project, _ = import_launch(launch, True, [relative], tmp_path)
    share = Path(project["nodes"]["talker"]["parameters"]["share"])
    assert share.is_absolute() and (share / "package.xml").is_file()


def test_ros1_params_outside_nodes_are_the_parameter_servers(tmp_path: Path) -> None:
    """ROS 1's parameter server: /outer/inner/b and /outer/d, set in groups that hold no node, are the
    project's global parameters by their full names (the node in /outer reads them as inner/b and d, as
    rospy resolves them); a node's own <param> is its private one."""
    launch = tmp_path / "t.launch"
    launch.write_text(
        '<launch>\n  <group ns="outer">\n    <node pkg="rospy_tutorials" type="talker.py" name="talker"/>\n'
        '    <group ns="inner"><param name="b" value="3"/></group>\n    <group><param name="d" value="5"/></group>\n'
        '  </group>\n  <group ns="elsewhere"><param name="e" value="6"/></group>\n</launch>\n')
    project, _ = import_launch(launch, False, [ROS1_PACKAGES], tmp_path)
    assert project["parameters"] == {"/outer/inner/b": 3, "/outer/d": 5, "/elsewhere/e": 6}
    assert "parameters" not in project["nodes"]["talker"]
    launch.write_text('<launch>\n  <param name="/top" value="1"/>\n  <node pkg="rospy_tutorials" type="talker.py" '
                      'name="talker" args="chatter:=speech _rate:=5 __ns:=/r2 extra">\n'
                      '    <param name="private" value="2"/>\n  </node>\n</launch>\n')
    project, _ = import_launch(launch, False, [ROS1_PACKAGES], tmp_path)
    talker = project["nodes"]["talker"]
    assert project["parameters"] == {"/top": 1}
    assert talker["parameters"] == {"private": 2, "rate": 5}  # _rate:= is a private parameter
    assert (talker["remap"], talker["namespace"], talker["args"]) == ({"chatter": "speech"}, "/r2", ["extra"])
