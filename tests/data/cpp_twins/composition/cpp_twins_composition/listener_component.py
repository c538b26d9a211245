"""A Python port of composition's Listener component: logs what it hears on chatter."""

from rclpy.node import Node
from std_msgs.msg import String


class Listener(Node):

    def __init__(self):
        super().__init__('listener')
        self.sub = self.create_subscription(String, 'chatter', self.callback, 10)

    def callback(self, msg):
        self.get_logger().info('I heard: [%s]' % msg.data)
