"""A Python port of composition's Talker component: 'Hello World: N' on chatter once a second."""

from rclpy.node import Node
from std_msgs.msg import String


class Talker(Node):

    def __init__(self):
        super().__init__('talker')
        self.count = 0
        self.pub = self.create_publisher(String, 'chatter', 10)
        self.timer = self.create_timer(1.0, self.on_timer)

    def on_timer(self):
        self.count += 1
        msg = String(data='Hello World: %d' % self.count)
        self.get_logger().info("Publishing: '%s'" % msg.data)
        self.pub.publish(msg)
