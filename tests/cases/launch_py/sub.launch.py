from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument("who"),
        Node(package="demo_nodes_cpp", executable="listener", name=LaunchConfiguration("who"), namespace="sub"),
    ])
