"""Controller -> inverse kinematics -> servo, as in ReconROS's ball-on-plate station."""

import numpy as np
from kinematics import pack, servo_angles, to_pwm, unpack

from hetros import Node
from hetros.interfaces.std_msgs.msg import UInt32
from hetros.interfaces.stewart_msgs.msg import ServoPwm


def controller(node: Node) -> None:
    pub = node.create_publisher(UInt32, "/platform_angles")
    sub = node.create_subscription(ServoPwm, "/servo_pwm")
    rng = np.random.default_rng(node.get_parameter("seed", 7))
    for _ in range(node.get_parameter("commands", 20)):
        x, y = (float(v) for v in rng.uniform(-8.0, 8.0, 2))
        command = pack(x, y)
        pub.publish(UInt32(data=command))
        result = sub.take(timeout=10.0)
        if result.command != command:
            raise ValueError(f"answer for {result.command:#x}, expected {command:#x}")
        node.log.info("command %#010x -> pwm %s", command, " ".join(str(int(v)) for v in result.pwm))


def inverse(node: Node) -> None:
    pub = node.create_publisher(ServoPwm, "/servo_pwm")
    for msg in node.create_subscription(UInt32, "/platform_angles"):
        x, y = unpack(msg.data)
        pub.publish(ServoPwm(command=msg.data, pwm=to_pwm(servo_angles(x, y))))
