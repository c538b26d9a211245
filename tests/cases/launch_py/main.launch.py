"""A launch file that uses what ROS 2 launch files use (hetros's own test case)."""

import os

from launch import LaunchDescription
from launch.actions import (
    DeclareLaunchArgument,
    EmitEvent,
    GroupAction,
    IncludeLaunchDescription,
    LogInfo,
    OpaqueFunction,
    RegisterEventHandler,
    SetEnvironmentVariable,
    TimerAction,
)
from launch.conditions import IfCondition, LaunchConfigurationEquals, UnlessCondition
from launch.event_handlers import OnProcessExit
from launch.events import Shutdown
from launch.launch_description_sources import AnyLaunchDescriptionSource, PythonLaunchDescriptionSource
from launch.substitutions import (
    EnvironmentVariable,
    LaunchConfiguration,
    PathJoinSubstitution,
    PythonExpression,
    TextSubstitution,
    ThisLaunchFileDir,
)
from launch_ros.actions import Node, PushRosNamespace, SetParameter, SetRemap
from launch_ros.substitutions import FindPackageShare


def more_listeners(context, count):
    how_many = int(context.launch_configurations["listeners"]) + count
    return [Node(package="demo_nodes_cpp", executable="listener", name=f"extra{i}", namespace="extra")
            for i in range(how_many)]


def generate_launch_description():
    talker = Node(package="demo_nodes_cpp", executable="talker", name=[LaunchConfiguration("prefix"), "talker"],
                  parameters=[{"rate": LaunchConfiguration("rate"), "nested": {"gain": 2.5, "name": "x"}},
                              PathJoinSubstitution([ThisLaunchFileDir(), "config", "params.yaml"])],
                  remappings=[("chatter", "speech")],
                  arguments=["--flag", "--ros-args", "-r", "extra:=other", "-p", "from_cli:=7"])
    return LaunchDescription([
        DeclareLaunchArgument("prefix", default_value="my_"),
        DeclareLaunchArgument("rate", default_value="2.0"),
        DeclareLaunchArgument("with_group", default_value="true"),
        DeclareLaunchArgument("listeners", default_value="1", choices=["0", "1", "2"]),
        SetEnvironmentVariable("HETROS_CASE", "yes"),
        talker,
        Node(package="demo_nodes_cpp", executable="listener", name="skipped",
             condition=UnlessCondition(LaunchConfiguration("with_group"))),
        GroupAction([
            PushRosNamespace("robot"),
            SetRemap("chatter", "/speech"),
            SetParameter("use_sim_time", True),
            Node(package="demo_nodes_cpp", executable="listener", name="grouped",
                 parameters=[{"label": EnvironmentVariable("HETROS_CASE"),
                              "share": FindPackageShare("demo_nodes_cpp")}]),
        ], condition=IfCondition(LaunchConfiguration("with_group"))),
        Node(package="demo_nodes_cpp", executable="listener", name="outside",
             condition=IfCondition(PythonExpression(["'", LaunchConfiguration("prefix"), "' == 'my_'"]))),
        IncludeLaunchDescription(PythonLaunchDescriptionSource([ThisLaunchFileDir(), "/sub.launch.py"]),
                                 launch_arguments={"who": "included"}.items()),
        IncludeLaunchDescription(AnyLaunchDescriptionSource(os.path.join(os.path.dirname(__file__), "sub.launch.xml")),
                                 launch_arguments=[("who", TextSubstitution(text="from_xml"))]),
        OpaqueFunction(function=more_listeners, args=[1]),
        TimerAction(period=2.0, actions=[LogInfo(msg="later")]),
        RegisterEventHandler(OnProcessExit(target_action=talker, on_exit=[EmitEvent(event=Shutdown())])),
        Node(package="demo_nodes_cpp", executable="listener", name="equal",
             condition=LaunchConfigurationEquals("listeners", "1")),
    ])
