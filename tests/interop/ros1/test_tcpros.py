"""hetros' ROS 1 peer (slave API + TCPROS) against stock rospy nodes from Debian."""

from __future__ import annotations

import contextlib
import logging
import socket
import subprocess
import textwrap
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hetros.msg import registry
from hetros.transport.tcpros import Ros1Peer, Ros1Type
from tests.support.ros1 import LISTENER, ROS_PYTHON, TALKER, free_port, needs_ros1, run_ros, stop

pytestmark = needs_ros1

TYPES = registry()
String = TYPES.get("std_msgs/msg/String")
Image = TYPES.get("sensor_msgs/msg/Image")

# a stock rospy node that sends every image it gets back on another topic
IMAGE_ECHO = textwrap.dedent("""
    import rospy
    from sensor_msgs.msg import Image
    rospy.init_node("image_echo")
    back = rospy.Publisher("/img_back", Image, queue_size=10)
    rospy.Subscriber("/img_out", Image, back.publish)
    rospy.spin()
""")


def _wait(condition: Any, seconds: float = 20.0) -> bool:
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


@contextlib.contextmanager
def _talking(publication: Any, text: str) -> Iterator[None]:
    """Publish ``text`` every 50 ms from a thread while the block runs."""
    stop = threading.Event()

    def talk() -> None:
        while not stop.is_set():
            publication.publish(String(data=text))
            time.sleep(0.05)

    thread = threading.Thread(target=talk, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def _spawn(script: str, tmp_path: Path, name: str, env: dict[str, str]) -> subprocess.Popen[str]:
    path = tmp_path / f"{name}.py"
    path.write_text(script)
    return subprocess.Popen([ROS_PYTHON, str(path)], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)


def test_hetros_publishes_to_a_rospy_subscriber(ros_master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    uri, env = ros_master
    peer = Ros1Peer("/hetros_talker", uri)
    publication = peer.advertise("/chatter", Ros1Type(TYPES, "std_msgs/msg/String"))
    try:
        with _talking(publication, "hello"):
            out, _ = _spawn(LISTENER, tmp_path, "listener", env).communicate(timeout=40)
            info = run_ros(env, "rosnode", "info", "/hetros_talker")
            try:
                subprocess.run(["rostopic", "hz", "-w", "5", "/chatter"], env=env, capture_output=True, text=True,
                               timeout=6, check=False)
                rate = ""
            except subprocess.TimeoutExpired as expired:  # rostopic hz runs until stopped
                rate = expired.stdout.decode() if isinstance(expired.stdout, bytes) else (expired.stdout or "")
        assert out.strip() == "got 5 hello", out
        assert "/chatter [std_msgs/String]" in info and "Pid:" in info, info
        rates = [float(line.split(":")[1]) for line in rate.splitlines() if line.startswith("average rate:")]
        assert rates and 10 < rates[-1] < 25, rate  # published every 50 ms
    finally:
        peer.close()


def test_hetros_receives_from_a_rospy_publisher(ros_master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    uri, env = ros_master
    talker = _spawn(TALKER, tmp_path, "talker", env)
    peer = Ros1Peer("/hetros_listener", uri)
    got: list[Any] = []
    try:
        peer.subscribe("/chatter", Ros1Type(TYPES, "std_msgs/msg/String"), got.append)
        assert _wait(lambda: len(got) >= 5), f"received {len(got)}"
        assert got[-1].data.startswith("hello ") and got[-1].is_frozen
    finally:
        peer.close()
        stop(talker)


def test_an_image_with_a_header_round_trips_through_stock_rospy(ros_master: tuple[str, dict[str, str]],
                                                                tmp_path: Path) -> None:
    """ROS 1's Header has seq and ROS 1's Image another md5: the mapping holds against the real thing."""
    uri, env = ros_master
    echo = _spawn(IMAGE_ECHO, tmp_path, "image_echo", env)
    peer = Ros1Peer("/hetros_camera", uri)
    kind = Ros1Type(TYPES, "sensor_msgs/msg/Image")
    assert kind.md5 == "060021388200f6f0f447d0fcd9c64743"
    back: list[Any] = []
    try:
        peer.subscribe("/img_back", kind, back.append)
        out = peer.advertise("/img_out", kind)
        image = Image(height=2, width=3, encoding="rgb8", step=9, data=np.arange(18, dtype=np.uint8))
        image.header.frame_id = "camera"
        image.header.stamp.sec, image.header.stamp.nanosec = 7, 500
        assert _wait(lambda: (out.publish(image), bool(back))[1], 30), "no image came back"
        assert back[0] == image
    finally:
        peer.close()
        stop(echo)


def test_a_type_mismatch_is_refused_naming_both_types_and_md5s(ros_master: tuple[str, dict[str, str]], tmp_path: Path,
                                                               caplog: pytest.LogCaptureFixture) -> None:
    uri, env = ros_master
    peer = Ros1Peer("/hetros_talker", uri)
    publication = peer.advertise("/numbers", Ros1Type(TYPES, "std_msgs/msg/String"))
    wrong = textwrap.dedent("""
        import rospy, time
        from std_msgs.msg import Int32
        rospy.init_node("wrong_listener")
        rospy.Subscriber("/numbers", Int32, lambda m: None)
        time.sleep(4)
    """)
    with caplog.at_level(logging.ERROR, logger="hetros.ros1"):
        listener = _spawn(wrong, tmp_path, "wrong", env)
        assert _wait(lambda: "md5" in caplog.text, 30), caplog.text
        listener.wait(30)
    line = next(r.getMessage() for r in caplog.records if "md5" in r.getMessage())
    assert "/numbers" in line and "std_msgs/Int32" in line and "std_msgs/String" in line
    assert "da5909fbe378aeaf85e547e830cc1bb7" in line and Ros1Type(TYPES, "std_msgs/msg/String").md5 in line
    publication.publish(String(data="still fine"))
    peer.close()


def test_a_peer_sending_garbage_is_dropped_and_the_node_goes_on(ros_master: tuple[str, dict[str, str]], tmp_path: Path,
                                                                 caplog: pytest.LogCaptureFixture) -> None:
    uri, env = ros_master
    peer = Ros1Peer("/hetros_talker", uri)
    publication = peer.advertise("/chatter", Ros1Type(TYPES, "std_msgs/msg/String"))
    with caplog.at_level(logging.ERROR, logger="hetros.ros1"):
        for junk in (b"\xff\xff\xff\xff", b"\x08\x00\x00\x00\x04\x00\x00\x00abcd", b"GET / HTTP/1.0\r\n\r\n"):
            with socket.create_connection(("127.0.0.1", peer.tcpros_port)) as sock:
                sock.sendall(junk)
                sock.settimeout(5)
                try:
                    sock.recv(4096)
                except OSError:
                    pass
    assert "announces 4294967295 bytes" in caplog.text
    assert "is not name=value" in caplog.text
    try:
        with _talking(publication, "hello after garbage"):
            out, _ = _spawn(LISTENER, tmp_path, "listener", env).communicate(timeout=40)
        assert out.strip().startswith("got 5 hello after garbage"), out
    finally:
        peer.close()


def test_a_master_that_is_down_at_start_is_retried(caplog: pytest.LogCaptureFixture) -> None:
    from hetros.transport.tcpros import Master

    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    started: list[Master] = []
    timer = threading.Timer(1.5, lambda: started.append(Master("127.0.0.1", port)))
    with caplog.at_level(logging.WARNING, logger="hetros.ros1"):
        peer = Ros1Peer("/early", uri)
        timer.start()
        peer.advertise("/t", Ros1Type(TYPES, "std_msgs/msg/String"))
    assert f"ROS master at {uri} unreachable" in caplog.text and "retrying" in caplog.text
    # the master answers as soon as it listens, which may be before its constructor returned to the timer
    timer.join(10)
    assert started and started[0].state.getSystemState("/x")[2][0] == [["/t", ["/early"]]]
    peer.close()
    started[0].close()


def test_the_guides_ros1_peer_example_runs() -> None:
    from hetros.transport.tcpros import Master

    guide = (Path(__file__).resolve().parents[3] / "docs" / "GUIDE.md").read_text()
    block = guide.split("### A process as a ROS 1 node", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    running = Master("127.0.0.1", free_port())
    namespace: dict[str, Any] = {}
    try:
        exec(block.replace("http://127.0.0.1:11311/", running.uri), namespace)
        assert namespace["chatter"].topic == "/chatter"
    finally:
        if "peer" in namespace:
            namespace["peer"].close()
        running.close()


ROS1_SERVER = textwrap.dedent("""
    import rospy
    from std_srvs.srv import SetBool, SetBoolResponse
    rospy.init_node("ros1_server")
    rospy.Service("/ros1_toggle", SetBool, lambda req: SetBoolResponse(success=req.data, message="ros1 %s" % req.data))
    rospy.spin()
""")

ROS1_CLIENT = textwrap.dedent("""
    import rospy
    from std_srvs.srv import SetBool
    rospy.wait_for_service("/hetros_toggle", 20)
    proxy = rospy.ServiceProxy("/hetros_toggle", SetBool, persistent=True)
    print(proxy(True).message, proxy(True).message)
    try:
        rospy.ServiceProxy("/hetros_toggle", SetBool)(False)
    except rospy.ServiceException as exc:
        print("refused:", exc)
""")


def test_services_both_ways_with_rospy(ros_master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    from hetros.transport.tcpros._types import Ros1ServiceType

    uri, env = ros_master
    SetBool = TYPES.get_service("std_srvs/srv/SetBool")
    kind = Ros1ServiceType(TYPES, "std_srvs/srv/SetBool")
    server = _spawn(ROS1_SERVER, tmp_path, "server", env)
    peer = Ros1Peer("/hetros_services", uri)

    def toggle(request: Any) -> Any:
        if not request.data:
            raise ValueError("refusing false")
        return SetBool.Response(success=True, message="hetros says yes")

    try:
        peer.advertise_service("/hetros_toggle", kind, toggle)
        client = _spawn(ROS1_CLIENT, tmp_path, "client", env)
        out, _ = client.communicate(timeout=60)
        assert "hetros says yes hetros says yes" in out, out
        assert "refused:" in out and "ValueError: refusing false" in out, out
        assert _wait(lambda: "/ros1_toggle" in str(xmlrpc_state(uri)), 30)
        response = peer.call_service("/ros1_toggle", kind, SetBool.Request(data=True))
        assert (response.success, response.message) == (True, "ros1 True")
    finally:
        peer.close()
        stop(server)


def xmlrpc_state(uri: str) -> Any:
    import xmlrpc.client

    return xmlrpc.client.ServerProxy(uri).getSystemState("/test")[2]


def test_running_connections_survive_the_master_going_away(tmp_path: Path) -> None:
    """As in ROS 1: the master is needed to connect, not to keep talking."""
    from tests.support.ros1 import ros1_master

    masters = ros1_master()
    uri, env = next(masters)
    peer = Ros1Peer("/hetros_talker", uri)
    publication = peer.advertise("/chatter", Ros1Type(TYPES, "std_msgs/msg/String"))
    counter = textwrap.dedent("""
        import sys, time, rospy
        from std_msgs.msg import String
        got = []
        rospy.init_node("counter")
        rospy.Subscriber("/chatter", String, lambda m: got.append(m.data))
        while not got:
            time.sleep(0.05)
        print("connected", flush=True)
        sys.stdin.readline()  # the test stops the master here
        before = len(got)
        time.sleep(2)
        print("after", len(got) - before, flush=True)
    """)
    listener = subprocess.Popen([ROS_PYTHON, "-c", counter], env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
    try:
        with _talking(publication, "still here"):
            assert listener.stdout is not None and listener.stdin is not None
            assert listener.stdout.readline().strip() == "connected"
            next(masters, None)  # stops the master
            listener.stdin.write("\n")
            listener.stdin.flush()
            out, _ = listener.communicate(timeout=30)
        assert out.startswith("after ") and int(out.split()[1]) > 10, out
    finally:
        listener.kill()
        peer.close()
