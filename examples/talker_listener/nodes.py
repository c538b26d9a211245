"""The ROS-lite paper's example (Fig. 6): one talker, two listeners on /chatter."""

from hetros import Node
from hetros.interfaces.std_msgs.msg import String


def talker(node: Node) -> None:
    pub = node.create_publisher(String, "/chatter")
    count = node.get_parameter("count", 0)
    for i in node.rate(node.get_parameter("hz", 10.0)):
        pub.publish(String(data=f"hello world {i}"))
        if count and i + 1 >= count:
            break


def listener(node: Node) -> None:
    node.create_subscription(String, "/chatter", lambda msg: node.log.info("I heard: [%s]", msg.data))


def listener2(node: Node) -> None:
    for msg in node.create_subscription(String, "/chatter"):
        node.log.info("I heard: [%s]", msg.data)
