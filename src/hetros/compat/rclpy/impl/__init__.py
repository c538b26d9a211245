"""rclpy.impl: the pieces of rclpy's implementation that ROS code imports directly."""
