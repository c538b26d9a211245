"""Stock ROS 1 from Debian as a test peer: a running `hetros master` and rospy node scripts."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import textwrap
import time
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

ROS_PYTHON = "/usr/bin/python3"


def _has_rospy() -> bool:
    probe = "import rospy, rostopic, rosparam, rosservice, rosnode, sensor_msgs.msg"
    try:
        return subprocess.run([ROS_PYTHON, "-c", probe], capture_output=True, timeout=30, check=False).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


needs_ros1 = pytest.mark.skipif(not _has_rospy(), reason="Debian's python3-rospy and ROS tools are not installed "
                                                          "(`make test` installs them when run as root)")


def _has_roscpp() -> bool:
    try:
        flags = subprocess.run(["pkg-config", "--exists", "roscpp"], capture_output=True, timeout=30, check=False)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return flags.returncode == 0 and shutil.which("g++") is not None and os.path.exists("/usr/include/std_srvs")


needs_roscpp = pytest.mark.skipif(not _has_roscpp(), reason="Debian's libroscpp-dev, libstd-srvs-dev, g++ or "
                                                            "pkg-config is missing (`make test` installs them as root)")


def compile_roscpp(source: Path, binary: Path) -> Path:
    """Build a roscpp node as a ROS 1 user would (g++ and Debian's roscpp)."""
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "roscpp"], capture_output=True, text=True,
                           check=True).stdout.split()
    built = subprocess.run(["g++", "-O1", "-o", str(binary), str(source), *flags], capture_output=True, text=True,
                           timeout=300, check=False)
    assert built.returncode == 0, f"compiling {source} failed: {built.stderr}"
    return binary


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


ROSMASTER = "/usr/bin/rosmaster"


def stop(proc: subprocess.Popen[str], grace: float = 15) -> str:
    """Terminate a peer and return what it printed.

    The output is drained while waiting: a chatty rospy node blocked on a full stdout pipe
    cannot finish its shutdown, and a slow one on a loaded machine is killed after ``grace``
    rather than failing the test that was only cleaning up.
    """
    if proc.poll() is None:
        proc.terminate()
    try:
        out = proc.communicate(timeout=grace)[0]
    except subprocess.TimeoutExpired:
        proc.kill()
        out = proc.communicate()[0]
    return out or ""


def ros1_master(kind: str = "hetros") -> Iterator[tuple[str, dict[str, str]]]:
    """A running master on a free port: ``hetros master``, or Debian's ``rosmaster``."""
    port = free_port()
    command = [sys.executable, "-m", "hetros", "master", "--port", str(port)] if kind == "hetros" else \
        [ROS_PYTHON, ROSMASTER, "--core", "-p", str(port)]
    ros_env = dict(os.environ, ROS_HOME="/tmp/hetros-test-ros-home")
    ros_env.pop("PYTHONPATH", None)
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=ros_env if kind != "hetros" else None)
    uri = f"http://127.0.0.1:{port}/"
    deadline = time.monotonic() + 20
    while True:
        try:
            xmlrpc.client.ServerProxy(uri).getPid("/test")
            break
        except OSError:
            if time.monotonic() > deadline or proc.poll() is not None:
                proc.kill()
                raise AssertionError(f"{kind} master did not come up: {proc.communicate()[0]}") from None
            time.sleep(0.1)
    env = dict(os.environ, ROS_MASTER_URI=uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME="/tmp/hetros-test-ros-home")
    env.pop("PYTHONPATH", None)
    yield uri, env
    stop(proc)


def rospy_talker(name: str = "talker", topic: str = "/chatter", text: str = "hello", hz: int = 20) -> str:
    """A stock rospy talker's script: ``<text> <i>`` on ``topic`` at ``hz``, until shut down."""
    return textwrap.dedent(f"""
        import rospy
        from std_msgs.msg import String
        rospy.init_node("{name}")
        rospy.set_param("~rate", {hz})
        pub = rospy.Publisher("{topic}", String, queue_size=10)
        rate = rospy.Rate({hz})
        i = 0
        while not rospy.is_shutdown():
            pub.publish(String(data="{text} %d" % i))
            i += 1
            rate.sleep()
    """)


TALKER = rospy_talker()

LISTENER = textwrap.dedent("""
    import sys, time, rospy
    from std_msgs.msg import String
    got = []
    rospy.init_node("listener")
    rospy.Subscriber("/chatter", String, lambda m: got.append(m.data))
    start = time.time()
    while len(got) < 5 and time.time() - start < 20:
        time.sleep(0.05)
    print("got", min(len(got), 5), got[-1] if got else "")
""")


def run_ros(env: dict[str, str], *args: str, timeout: float = 30) -> str:
    proc = subprocess.run(list(args), env=env, capture_output=True, text=True, timeout=timeout, check=False)
    assert proc.returncode == 0, f"{' '.join(args)} failed: {proc.stdout}{proc.stderr}"
    return proc.stdout


