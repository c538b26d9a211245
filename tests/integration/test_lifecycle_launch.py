"""Managed nodes as ROS 2 runs them: ros2/demos's lifecycle_py talker, unchanged, under its own launch
file, driven by the C++ demo's service client (a Python twin), by `hetros lifecycle` as `ros2 lifecycle`
drives it, and brought to a state by the project's `lifecycle:`; the listener hears only while the talker
is active."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import yaml

from tests.support.cli import hetros_in, private_env

DATA = Path(__file__).resolve().parents[1] / "data"
TWINS = DATA / "cpp_twins"
LIFECYCLE_PY = DATA / "ros2_demos" / "lifecycle_py"




def _said(err: str, node: str) -> list[str]:
    form = re.compile(rf"^\[INFO\] \[\d+\.\d{{9}}\] \[{re.escape(node)}\]: (.*)$")
    return [m.group(1) for line in err.splitlines() if (m := form.match(line))]


def _heard_only_while_active(err: str) -> list[str]:
    """The listener's messages, checked to be exactly those the talker published while active."""
    published = [line.split("Publishing: [", 1)[1].rstrip("]") for line in _said(err, "lc_talker")
                 if line.startswith("Lifecycle publisher is active")]
    heard = [line.removeprefix("data_callback: ") for line in _said(err, "lc_listener")
             if line.startswith("data_callback: ")]
    assert heard and set(heard) <= set(published), err
    inactive_counts = {int(line.split("#")[1]) for line in _said(err, "lc_talker") if "HelloWorld #" in line
                       and "active. Publishing" not in line}
    assert not {int(h.split("#")[1]) for h in heard} & inactive_counts
    return heard


def test_lifecycle_pys_launch_file_with_the_demos_service_client(tmp_path: Path) -> None:
    done = hetros_in("launch", str(LIFECYCLE_PY / "launch" / "lifecycle_demo_launch.py"), "--package-path", str(TWINS),
                   "--duration", "22", cwd=tmp_path, timeout=120)
    assert done.returncode == 0, done.stderr
    client = _said(done.stderr, "lc_client")
    assert [line for line in client if "successfully triggered" in line] == [
        f"Transition {t} successfully triggered." for t in (1, 3, 4, 3, 4, 2, 5)], done.stderr
    assert client[-1] == "Node lc_talker has current state finalized.", done.stderr
    heard = _heard_only_while_active(done.stderr)
    assert len(heard) >= 2
    events = [line for line in _said(done.stderr, "lc_listener") if line.startswith("notify callback")]
    assert "notify callback: Transition from state activating to active" in events
    assert events[-1] == "notify callback: Transition from state shuttingdown to finalized", done.stderr


def _project(tmp_path: Path, state: str) -> Path:
    project = {
        "name": "lifecycle_cli",
        "python_path": [os.path.relpath(TWINS / "lifecycle", tmp_path)],
        "targets": {"talker": {"kind": "process"}, "listener": {"kind": "process"}},
        "nodes": {
            "lc_talker": {"run": "lifecycle_py.talker:main", "target": "talker", "lifecycle": state,
                          "publish": {"/lifecycle_chatter": "std_msgs/msg/String"}},
            "lc_listener": {"run": "cpp_twins_lifecycle.lifecycle_listener:main", "target": "listener",
                            "subscribe": {"/lifecycle_chatter": "std_msgs/msg/String",
                                          "/lc_talker/transition_event": "lifecycle_msgs/msg/TransitionEvent"}}},
        "topics": {"/lifecycle_chatter": {"history": "keep_last", "depth": 10}}}
    path = tmp_path / "project.yaml"
    path.write_text(yaml.safe_dump(project))
    return path


def test_hetros_lifecycle_drives_a_managed_node_as_ros2_lifecycle_does(tmp_path: Path) -> None:
    path = _project(tmp_path, "unconfigured")
    launched = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(path), "--duration", "30"],
                                cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=private_env(tmp_path))
    try:
        deadline = time.monotonic() + 30
        while hetros_in("lifecycle", "get", "/lc_talker", cwd=tmp_path).stdout.strip() != "unconfigured [1]":
            assert time.monotonic() < deadline, "the managed node never answered"
            time.sleep(0.3)
        assert hetros_in("lifecycle", "nodes", cwd=tmp_path).stdout == "/lc_talker\n"
        assert hetros_in("lifecycle", "list", "/lc_talker", cwd=tmp_path).stdout == (
            "- configure [1]\n\tStart: unconfigured\n\tGoal: configuring\n"
            "- shutdown [5]\n\tStart: unconfigured\n\tGoal: shuttingdown\n")
        refused = hetros_in("lifecycle", "set", "/lc_talker", "activate", cwd=tmp_path)
        assert refused.returncode == 1
        assert refused.stderr == "Unknown transition requested, available ones are:\n- configure [1]\n- shutdown [5]\n"
        for transition in ("configure", "activate"):
            done = hetros_in("lifecycle", "set", "/lc_talker", transition, cwd=tmp_path)
            assert (done.returncode, done.stdout) == (0, "Transitioning successful\n"), done.stderr
        assert hetros_in("lifecycle", "get", cwd=tmp_path).stdout == "/lc_talker: active [3]\n"
        time.sleep(2.5)  # the talker publishes once a second
        for transition in ("deactivate", "cleanup", "shutdown"):
            done = hetros_in("lifecycle", "set", "/lc_talker", transition, cwd=tmp_path)
            assert (done.returncode, done.stdout) == (0, "Transitioning successful\n"), done.stderr
        assert hetros_in("lifecycle", "get", "/lc_talker", cwd=tmp_path).stdout == "finalized [4]\n"
    finally:
        launched.terminate()
        _, err = launched.communicate(timeout=60)
    assert len(_heard_only_while_active(err)) >= 2


def test_the_project_brings_a_managed_node_to_its_state(tmp_path: Path) -> None:
    done = hetros_in("launch", str(_project(tmp_path, "active")), "--duration", "4", cwd=tmp_path, timeout=90)
    assert done.returncode == 0, done.stderr
    assert "on_configure() is called." in _said(done.stderr, "lc_talker")
    assert len(_heard_only_while_active(done.stderr)) >= 2
