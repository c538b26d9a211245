"""An rclpy node whose publisher chooses best effort in code (a check case: against a reliable topic QoS)."""
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import String


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("a")
    node.create_publisher(String, "/x", QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT))
    rclpy.spin(node)
