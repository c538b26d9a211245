"""Launch-file import edge cases, as ROS resolves them: ``$(file-content)``, a YAML group written as a list
of actions, and a relative ``--package-path`` whose ``$(find)`` must still name the package."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from hetros import ProjectError
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
    with pytest.raises(Exception, match=r"demo.launch.xml:2: \$\(file-content\) \S*no.txt does not exist"):
        import_launch(launch, True, [ROS2_PACKAGES], tmp_path)


def test_what_a_hostile_launch_file_asks_is_refused_by_name(tmp_path: Path) -> None:
    """Include loops, includes without end, $(eval) and $(file-content) of a device: each refused at its line,
    never followed, never read."""
    loop_a, loop_b = tmp_path / "a.launch.xml", tmp_path / "b.launch.xml"
    loop_a.write_text('<launch>\n  <include file="b.launch.xml"/>\n</launch>\n')
    loop_b.write_text('<launch>\n  <include file="a.launch.xml"/>\n</launch>\n')
    with pytest.raises(ProjectError, match=r"an include loop: .*a.launch.xml -> .*b.launch.xml -> .*a.launch.xml"):
        import_launch(loop_a, True, [ROS2_PACKAGES], tmp_path)
    fan = tmp_path / "fan.launch.xml"  # includes itself under ten arguments: 10**depth files
    fan.write_text("<launch>\n" + "".join(f'  <group><include file="fan{i}.launch.xml"/></group>\n'
                                           for i in range(10)) + "</launch>\n")
    for i in range(10):
        (tmp_path / f"fan{i}.launch.xml").write_text(fan.read_text())
    with pytest.raises(ProjectError, match=r"an include loop|more than 1000 launch files"):
        import_launch(fan, True, [ROS2_PACKAGES], tmp_path)
    evaluated = tmp_path / "eval.launch.xml"
    evaluated.write_text('<launch>\n  <node pkg="p" exec="e" name="$(eval 1 + int(\'2\'))"/>\n</launch>\n')
    with pytest.raises(ProjectError, match=r"eval.launch.xml:2: .*\$\(eval.*hetros evaluates \$\(arg\)"):
        import_launch(evaluated, True, [ROS2_PACKAGES], tmp_path)
    device = tmp_path / "device.launch.xml"
    device.write_text('<launch>\n  <arg name="x" default="$(file-content /dev/zero)"/>\n</launch>\n')
    with pytest.raises(ProjectError, match=r"device.launch.xml:2: \$\(file-content\) /dev/zero is a character device"):
        import_launch(device, True, [ROS2_PACKAGES], tmp_path)


def test_file_content_from_outside_the_package_is_told_and_keeps_its_files_mode(tmp_path: Path) -> None:
    secret = tmp_path / "outside" / "key.txt"
    secret.parent.mkdir()
    secret.write_text("robot_9")
    secret.chmod(0o600)
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "package.xml").write_text("<package><name>pkg</name></package>")
    launch = package / "demo.launch.xml"
    launch.write_text(f'<launch>\n  <group>\n    <push-ros-namespace namespace="$(file-content {secret})"/>\n'
                      '    <node pkg="examples_rclpy_executors" exec="talker" name="talker"/>\n  </group>\n</launch>\n')
    project, notes = import_launch(launch, True, [ROS2_PACKAGES], tmp_path)
    assert project["nodes"]["talker"]["namespace"] == "/robot_9"
    assert any("read a file outside the launch file's package" in note for note in notes), notes
    assert notes.file_mode & 0o077 == 0


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
