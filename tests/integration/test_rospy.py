"""rospy nodes, unchanged, under `hetros launch` with the project `hetros init` writes for them: the
ros_tutorials talker/listener and add_two_ints server/client (tests/data/ros_tutorials, copied as they
are), each in a process of its own, and a stock Debian rospy listener hearing the unchanged talker
through the ROS 1 bridge."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import yaml

from tests.support.ros1 import ROS_PYTHON, free_port, needs_ros1

TUTORIALS = Path(__file__).resolve().parents[1] / "data" / "ros_tutorials"
RUN = f"{TUTORIALS}/rospy_tutorials"


def init(tmp_path: Path, folder: str) -> dict[str, Any]:
    """The project `hetros init` writes for a folder of rospy scripts."""
    made = subprocess.run([sys.executable, "-m", "hetros", "init", f"{RUN}/{folder}", "-o",
                           str(tmp_path / "project.yaml"), "--name", "rospy_tutorials"],
                          capture_output=True, text=True, timeout=60, check=False)
    assert made.returncode == 0, made.stderr
    project: dict[str, Any] = yaml.safe_load((tmp_path / "project.yaml").read_text())
    return project


def init_scripts(tmp_path: Path, *scripts: str) -> dict[str, Any]:
    """The project `hetros init` writes for a folder holding these tutorial scripts (from several folders)."""
    import shutil

    folder = tmp_path / "scripts"
    folder.mkdir()
    for script in scripts:
        shutil.copy(f"{RUN}/{script}", folder)
    made = subprocess.run([sys.executable, "-m", "hetros", "init", str(folder), "-o", str(tmp_path / "project.yaml"),
                           "--name", "tutorials"], capture_output=True, text=True, timeout=60, check=False)
    assert made.returncode == 0, made.stderr
    project: dict[str, Any] = yaml.safe_load((tmp_path / "project.yaml").read_text())
    return project


def launch(tmp_path: Path, project: dict[str, Any], duration: float,
           env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    path = tmp_path / "project.yaml"
    path.write_text(yaml.safe_dump(project))
    environment = dict(env or os.environ)
    checked = subprocess.run([sys.executable, "-m", "hetros", "check", str(path)], capture_output=True, text=True,
                             env=environment, timeout=120, check=False)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    return subprocess.run([sys.executable, "-m", "hetros", "launch", str(path), "--duration", str(duration)],
                          capture_output=True, text=True, env=environment, timeout=120, check=False, cwd=tmp_path)


def test_the_talker_and_listener(tmp_path: Path) -> None:
    project = init(tmp_path, "001_talker_listener")
    assert project["nodes"]["talker"]["publish"] == {"chatter": "std_msgs/msg/String"}
    assert project["nodes"]["listener"]["subscribe"] == {"chatter": "std_msgs/msg/String"}
    assert project["targets"] == {"talker": {"kind": "process"}, "listener": {"kind": "process"}}
    done = launch(tmp_path, project, 2.5)
    assert done.returncode == 0, done.stderr
    # rospy's console form, as roslaunch shows it: [INFO] [walltime]: message
    said = re.findall(r"^\[INFO\] \[\d+\.\d{6}\]: (hello world [\d.]+)$", done.stderr, re.MULTILINE)
    heard = re.findall(r"^\[INFO\] \[\d+\.\d{6}\]: /listener_\d+_\d+I heard (hello world [\d.]+)$", done.stderr,
                       re.MULTILINE)
    assert len(said) >= 15 and heard[:10] == said[:10], done.stderr
    assert "Traceback" not in done.stderr


def test_three_subscriptions_to_one_topic_in_one_node_each_hear_every_message(tmp_path: Path) -> None:
    """003_listener_with_user_data, unchanged: three rospy.Subscribers on "chatter" in one node (userdata 1,
    2 and a tuple) and one on "chatter2", which nobody publishes (ROS lets it wait), beside 001's talker."""
    project = init_scripts(tmp_path, "003_listener_with_user_data/listener_with_user_data.py",
                           "001_talker_listener/talker.py")
    done = launch(tmp_path, project, 3.0)
    assert done.returncode == 0, done.stderr
    output = done.stdout + done.stderr
    first = re.findall(r"#1: I heard \[(hello world [\d.]+)\]", output)
    second = re.findall(r"#2: I heard \[(hello world [\d.]+)\]", output)
    third = re.findall(r"I heard \[(hello world [\d.]+)\] with userdata \[\('chatter1', 4\)\]", output)
    # the first subscription may hear a message or two before the script makes the others (as in ROS)
    assert len(second) >= 10 and second[:10] == third[:10], output
    assert second[0] in first and first[first.index(second[0]):][:10] == second[:10], output


def test_the_timer_talker_is_heard(tmp_path: Path) -> None:
    """001's talker_timer.py, unchanged: rospy.Timer at 10 Hz, its TimerEvent's current_real in each line."""
    project = init_scripts(tmp_path, "001_talker_timer/talker_timer.py", "001_talker_listener/listener.py")
    done = launch(tmp_path, project, 2.5)
    assert done.returncode == 0, done.stderr
    said = re.findall(r"^\[INFO\] \[[\d.]+\]: (hello world [\d.]+)$", done.stderr, re.MULTILINE)
    heard = re.findall(r"I heard (hello world [\d.]+)", done.stderr)
    assert len(said) >= 10 and said[:5] == heard[:5], done.stderr


def test_an_on_shutdown_hook_runs_once(tmp_path: Path) -> None:
    """008's publish_on_shutdown.py, unchanged: its hook prints and publishes "I'm dead!" once when the
    launch stops, and the listener hears it, as under roslaunch: a process with shutdown hooks is stopped
    before the others."""
    project = init_scripts(tmp_path, "008_on_shutdown/publish_on_shutdown.py", "001_talker_listener/listener.py")
    done = launch(tmp_path, project, 2.0)
    assert done.returncode == 0, done.stderr
    output = done.stdout + done.stderr
    assert output.count("I'm dead!") == 2, output  # printed by the hook, heard by the listener
    assert re.search(r"I heard I'm dead!$", output, re.MULTILINE), output


def test_the_advanced_publish_tutorial(tmp_path: Path) -> None:
    """009: publish(field values) in order and by keyword, resolve_name, get_num_connections, from its own
    launch file; nobody subscribes, as when nobody runs `rostopic echo`."""
    made = subprocess.run([sys.executable, "-m", "hetros", "import", "roslaunch",
                           f"{RUN}/009_advanced_publish/advanced_publish.launch", "--package-path", str(TUTORIALS),
                           "-o", str(tmp_path / "project.yaml")], capture_output=True, text=True, timeout=60,
                          check=False)
    assert made.returncode == 0, made.stderr
    project: dict[str, Any] = yaml.safe_load((tmp_path / "project.yaml").read_text())
    done = launch(tmp_path, project, 2.6)
    assert done.returncode == 0, done.stderr
    assert "To see messages, please type\n\t'rostopic echo /color'\nIn another window" in done.stdout, done.stdout
    assert re.findall(r"^\[INFO\] \[[\d.]+\]: (.*)$", done.stderr, re.MULTILINE)[:2] == ["I have 0 subscribers"] * 2


def test_what_hetros_has_no_counterpart_for_is_refused_naming_the_line(tmp_path: Path) -> None:
    """004 (SubscribeListener: a publisher told of each new peer, publishing to it alone) and 007 (the
    per-connection headers of ROS 1) are refused by hetros check at their line, with what to do instead."""
    project = init_scripts(tmp_path, "004_listener_subscribe_notify/listener_subscribe_notify.py",
                           "007_connection_header/listener_connection_header.py",
                           "007_connection_header/talker_connection_header.py")
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project))
    checked = subprocess.run([sys.executable, "-m", "hetros", "check", str(tmp_path / "project.yaml")],
                             capture_output=True, text=True, timeout=120, check=False)
    assert checked.returncode == 1
    assert re.search(r"listener_subscribe_notify\.py:45: uses SubscribeListener, which hetros has no counterpart "
                     r"for: .*publish to all", checked.stderr), checked.stderr
    assert re.search(r"listener_connection_header\.py:48: uses _connection_header, which hetros has no "
                     r"counterpart for", checked.stderr), checked.stderr


ROSPY_NAMES = '''
import rospy


def main() -> None:
    rospy.init_node("names")
    rospy.loginfo("resolved %s %s", rospy.resolve_name("chatter"), rospy.resolve_name("~private"))
    rospy.loginfo("search %s", rospy.search_param("rate"))
    rospy.delete_param("~rate")
    rospy.loginfo("after delete %s %s", rospy.has_param("rate"), rospy.search_param("rate"))
    try:
        rospy.delete_param("rate")
    except KeyError:
        rospy.loginfo("deleting twice is a KeyError")
'''


def test_rospy_names_and_parameters(tmp_path: Path) -> None:
    (tmp_path / "names.py").write_text(ROSPY_NAMES)
    project = {"name": "names", "targets": {"one": {"kind": "process"}},
               "nodes": {"names": {"run": "names:main", "target": "one", "namespace": "/robot",
                                   "parameters": {"rate": 5}}}}
    done = launch(tmp_path, project, 5)
    assert done.returncode == 0, done.stderr
    assert "resolved /robot/chatter /robot/names/private" in done.stderr
    assert "search /robot/names/rate" in done.stderr
    assert "after delete False None" in done.stderr
    assert "deleting twice is a KeyError" in done.stderr


def test_the_add_two_ints_server_and_client(tmp_path: Path) -> None:
    project = init(tmp_path, "005_add_two_ints")
    assert project["nodes"]["add_two_ints_server"]["services"] == {"add_two_ints": "rospy_tutorials/srv/AddTwoInts"}
    project["messages"] = [str(TUTORIALS / "msg")]  # the tutorials' .srv, kept apart in this copy
    project["nodes"]["add_two_ints_client"].update(args=["3", "4"], required=True)  # its command line
    done = launch(tmp_path, project, 30)
    assert done.returncode == 0, done.stderr
    assert "Requesting 3+4\n" in done.stdout and "3 + 4 = 7\n" in done.stdout, done.stdout + done.stderr
    assert done.stdout.count("Returning [3 + 4 = 7]\n") == 2  # the simplified and the formal call
    assert "Traceback" not in done.stderr


@needs_ros1
def test_a_stock_rospy_listener_hears_the_unchanged_talker(tmp_path: Path) -> None:
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}/", ROS_HOSTNAME="127.0.0.1")
    master = subprocess.Popen([sys.executable, "-m", "hetros", "master", "--port", str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    listener = None
    try:
        time.sleep(1.0)
        listener = subprocess.Popen([ROS_PYTHON, f"{RUN}/001_talker_listener/listener.py"], env=env, text=True,
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        project = init(tmp_path, "001_talker_listener")
        del project["nodes"]["listener"], project["targets"]["listener"]
        project["external"] = {"ros1": {"export": ["/chatter"]}}
        done = launch(tmp_path, project, 6, env)
        assert done.returncode == 0, done.stderr
    finally:
        if listener is not None:
            listener.terminate()
        master.terminate()
        master.wait(10)
    assert listener is not None
    try:
        heard, _ = listener.communicate(timeout=30)
    except subprocess.TimeoutExpired:  # rospy's own shutdown can wait for the master it lost; what it heard is kept
        listener.kill()
        heard, _ = listener.communicate(timeout=30)
    assert re.search(r"I heard hello world [\d.]+", heard), heard
