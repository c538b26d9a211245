"""The software around a ROS 1 node made of hardware (``project.yaml``).

``repeat``, ``points`` and ``mirror`` are the Python twins of ``hetros.hw.nodes:Echo``: with them on a
process target instead of the fpga one, the bridge frames in software and ROS 1 sees the same bytes.
"""

from pathlib import Path

from hetros import Node
from hetros.interfaces.geometry_msgs.msg import PointStamped
from hetros.interfaces.std_msgs.msg import String


def talker(node: Node) -> None:
    words = node.create_publisher(String, "/words")
    points = node.create_publisher(PointStamped, "/points_raw")
    for seq in node.rate(node.get_parameter("hz", 10.0)):
        words.publish(String(data=f"hello world {seq}"))
        point = PointStamped()
        point.header.frame_id = f"frame {seq}"  # a string before float64s: CDR pads, ROS 1 does not
        point.header.stamp.sec, point.header.stamp.nanosec = seq, 1000 * seq
        point.point.x, point.point.y, point.point.z = seq * 0.5, -1.0 * seq, 3.25
        points.publish(point)


def _echo(node: Node, kind: type[String] | type[PointStamped], source: str, sink: str) -> None:
    """Republish every message of ``source`` on ``sink`` (what the hardware Echo does)."""
    pub = node.create_publisher(kind, sink)
    node.create_subscription(kind, source, pub.publish)
    node.spin()


def repeat(node: Node) -> None:
    _echo(node, String, "/words", "/chatter")


def points(node: Node) -> None:
    _echo(node, PointStamped, "/points_raw", "/points")


def mirror(node: Node) -> None:
    _echo(node, String, "/ros1_chatter", "/mirrored")


def listener(node: Node) -> None:
    out = Path(node.get_parameter("out"))
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("a") as heard:
        for message in node.create_subscription(String, "/mirrored"):
            heard.write(f"heard {message.data}\n")
            heard.flush()
