"""`hetros import roslaunch|ros2launch`: talker and listener under a namespace, with a remap and a parameter
file, from a ROS 1 launch file and a ROS 2 launch file (XML and YAML); the imported projects check and run."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

DATA = Path(__file__).resolve().parents[1] / "data"
ROS1_PACKAGES = DATA / "ros_tutorials"
ROS2_PACKAGES = DATA / "ros2_examples" / "rclpy"

ROS1_LAUNCH = """<launch>
  <arg name="ns" default="demo"/>
  <group ns="$(arg ns)">
    <remap from="chatter" to="talk"/>
    <rosparam file="$(dirname)/params.yaml" command="load"/>
    <node pkg="rospy_tutorials" type="talker.py" name="talker">
      <param name="rate" value="10"/>
    </node>
    <node pkg="rospy_tutorials" type="listener.py" name="listener" unless="false"/>
    <node pkg="rospy_tutorials" type="listener.py" name="never" if="false"/>
  </group>
</launch>
"""

ROS2_XML = """<launch>
  <arg name="ns" default="demo"/>
  <group>
    <push-ros-namespace namespace="$(var ns)"/>
    <node pkg="examples_rclpy_executors" exec="talker" name="talker">
      <remap from="chatter" to="talk"/>
      <param from="$(dirname)/params.yaml"/>
      <param name="rate" value="10"/>
    </node>
    <node pkg="examples_rclpy_executors" exec="listener">
      <remap from="chatter" to="talk"/>
    </node>
  </group>
</launch>
"""

ROS2_YAML = """launch:
- arg: {name: ns, default: demo}
- group:
    children:
    - push-ros-namespace: {namespace: $(var ns)}
    - node:
        pkg: examples_rclpy_executors
        exec: talker
        name: talker
        remap: [{from: chatter, to: talk}]
        param: [{from: $(dirname)/params.yaml}, {name: rate, value: 10}]
    - node:
        pkg: examples_rclpy_executors
        exec: listener
        remap: [{from: chatter, to: talk}]
"""


def imported(tmp_path: Path, kind: str, name: str, text: str, params: str, packages: Path) -> dict[str, Any]:
    (tmp_path / name).write_text(text)
    (tmp_path / "params.yaml").write_text(params)
    made = subprocess.run([sys.executable, "-m", "hetros", "import", kind, str(tmp_path / name), "-o",
                           str(tmp_path / "project.yaml"), "--package-path", str(packages)],
                          capture_output=True, text=True, timeout=60, check=False)
    assert made.returncode == 0, made.stderr
    project: dict[str, Any] = yaml.safe_load((tmp_path / "project.yaml").read_text())
    return project


def run(tmp_path: Path, duration: float) -> subprocess.CompletedProcess[str]:
    """Check and launch the imported project as it was written (its python_path: finds the packages' code)."""
    project = str(tmp_path / "project.yaml")
    checked = subprocess.run([sys.executable, "-m", "hetros", "check", project], capture_output=True, text=True,
                             timeout=60, check=False)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    return subprocess.run([sys.executable, "-m", "hetros", "launch", project, "--duration", str(duration)],
                          capture_output=True, text=True, timeout=60, check=False, cwd=tmp_path)


def test_a_ros1_launch_file_imports_and_runs(tmp_path: Path) -> None:
    project = imported(tmp_path, "roslaunch", "talker_listener.launch", ROS1_LAUNCH, "greeting: hello\ngains: {p: 2}\n",
                       ROS1_PACKAGES)
    nodes = project["nodes"]
    assert set(nodes) == {"talker", "listener"}  # if="false" left one out
    for node in nodes.values():
        assert node["namespace"] == "/demo" and node["remap"] == {"chatter": "talk"}
        assert node["target"] in project["targets"]
    # a <rosparam> in the group is the parameter server's, under the group's namespace; the node's <param>
    # is its private one
    assert project["parameters"] == {"/demo/greeting": "hello", "/demo/gains/p": 2}
    assert nodes["talker"]["parameters"] == {"rate": 10}
    assert nodes["talker"]["publish"] == {"chatter": "std_msgs/msg/String"}
    done = run(tmp_path, 2.5)
    assert done.returncode == 0, done.stderr
    # rospy's console form; the launch file's name stands over the code's anonymous one, as under roslaunch
    heard = re.findall(r"^\[INFO\] \[[\d.]+\]: /demo/listenerI heard (hello world [\d.]+)$", done.stderr,
                       re.MULTILINE)
    assert len(heard) >= 5, done.stderr


@pytest.mark.parametrize(("name", "text"), [("talker_listener.launch.xml", ROS2_XML),
                                            ("talker_listener.launch.yaml", ROS2_YAML)])
def test_a_ros2_launch_file_imports_and_runs(tmp_path: Path, name: str, text: str) -> None:
    project = imported(tmp_path, "ros2launch", name, text,
                       "/**:\n  ros__parameters: {greeting: hello, gains: {p: 2}}\n", ROS2_PACKAGES)
    nodes = project["nodes"]
    assert set(nodes) == {"talker", "listener"}
    assert nodes["talker"]["parameters"] == {"greeting": "hello", "gains.p": 2, "rate": 10}
    assert nodes["listener"]["remap"] == {"chatter": "talk"} and nodes["listener"]["namespace"] == "/demo"
    assert nodes["talker"]["run"] == "examples_rclpy_executors.talker:main"
    if name.endswith(".yaml"):
        return  # the same project as the XML's: run once
    done = run(tmp_path, 2.6)
    assert done.returncode == 0, done.stderr
    assert '[demo.talker]: Publishing: "Hello World: 1"' in done.stderr
    assert '[demo.listener]: I heard: "Hello World: 1"' in done.stderr


@pytest.mark.parametrize(("text", "expected"), [
    ('<launch>\n  <node pkg="rospy_tutorials" type="talker.py" name="t" machine="robot"/>\n</launch>\n',
     "x.launch:2: <node machine=...> has no counterpart"),
    ('<launch>\n  <node pkg="nowhere" type="talker.py" name="t"/>\n</launch>\n',
     "x.launch:2: package 'nowhere' not found"),
    ('<launch>\n  <node pkg="rospy_tutorials" type="gone.py" name="t"/>\n</launch>\n',
     "x.launch:2: package rospy_tutorials has no executable 'gone.py'"),
    ('<launch>\n\n  <machine name="m"/>\n</launch>\n', "x.launch:3: <machine> has no counterpart"),
    ('<launch>\n  <node pkg="$(arg p)" type="t" name="t"/>\n</launch>\n', "x.launch:2: $(arg p): no such argument"),
    ("<launch>\n  <node\n</launch>\n", "x.launch:3: not valid XML"),
])
def test_what_a_launch_file_cannot_map_is_refused_naming_file_and_line(tmp_path: Path, text: str,
                                                                         expected: str) -> None:
    (tmp_path / "x.launch").write_text(text)
    made = subprocess.run([sys.executable, "-m", "hetros", "import", "roslaunch", str(tmp_path / "x.launch"),
                           "--package-path", str(ROS1_PACKAGES)], capture_output=True, text=True, timeout=60,
                          check=False)
    assert made.returncode != 0 and expected in made.stderr, made.stderr
