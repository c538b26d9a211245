from launch import LaunchDescription

DESCRIPTION = LaunchDescription([])
