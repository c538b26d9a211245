"""A Python port of ros2/demos's lifecycle_listener (C++): it hears the managed talker's data and its
transition events."""

import rclpy
from lifecycle_msgs.msg import TransitionEvent
from rclpy.node import Node
from std_msgs.msg import String


class LifecycleListener(Node):

    def __init__(self, node_name):
        super().__init__(node_name)
        self.sub_data = self.create_subscription(String, 'lifecycle_chatter', self.data_callback, 10)
        self.sub_notification = self.create_subscription(
            TransitionEvent, '/lc_talker/transition_event', self.notification_callback, 10)

    def data_callback(self, msg):
        self.get_logger().info('data_callback: %s' % msg.data)

    def notification_callback(self, msg):
        self.get_logger().info('notify callback: Transition from state %s to %s'
                               % (msg.start_state.label, msg.goal_state.label))


def main(args=None):
    rclpy.init(args=args)
    node = LifecycleListener('lc_listener')
    try:
        rclpy.spin(node)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
