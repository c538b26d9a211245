from launch import LaunchDescription


def generate_launch_description():
    robots = {}
    return LaunchDescription([robots["first"]])
