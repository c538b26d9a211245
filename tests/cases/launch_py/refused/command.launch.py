from launch import LaunchDescription
from launch.substitutions import Command
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        Node(package="demo_nodes_cpp", executable="talker",
             parameters=[{"robot_description": Command(["xacro", "r.xacro"])}]),
    ])
