"""ReconROS's ball-on-plate station (Fig. 7-8): Touch -> Control -> Inverse -> Servo -> plate.

- physics: the rolling ball on the tilting plate (a = 5/7 g sin(tilt) per axis), one
  20 ms step per tick, in lockstep with the platform pose the servos produce;
- touch: a resistive touchscreen reading of the ball, with noise;
- control: a Kalman filter (constant velocity) and a PID per axis -> two tilt angles,
  packed as Q8.6 into a uint32 (what the hardware inverse-kinematics node takes);
- inverse: the Stewart-platform kinematics -> six 10-bit PWM values;
- servo: PWM -> servo angles -> platform pose, by solving the forward kinematics.
"""

import sys
import time
from pathlib import Path

import numpy as np

sys.path.append(str(Path(__file__).resolve().parent.parent / "inverse_kinematics"))
from kinematics import pack, servo_angles, to_pwm, unpack

from hetros import Node
from hetros.interfaces.geometry_msgs.msg import Point, Vector3
from hetros.interfaces.plate_msgs.msg import BallState
from hetros.interfaces.std_msgs.msg import UInt32
from hetros.interfaces.stewart_msgs.msg import ServoPwm

DT = 0.02
HALF_PLATE = 0.10
MAX_TILT_DEG = 8.0
ROLLING = 5.0 / 7.0 * 9.81


def physics(node: Node) -> None:
    pub = node.create_publisher(BallState, "ball_state")
    pose = node.create_subscription(Vector3, "platform_pose")
    rng = np.random.default_rng(node.get_parameter("seed", 3))
    x, y = rng.uniform(-0.06, 0.06, 2)
    vx, vy = rng.uniform(-0.05, 0.05, 2)
    tilt_x = tilt_y = 0.0
    steps = round(node.get_parameter("seconds", 10.0) / DT)
    worst = 0.0
    settled_at = None
    for step in node.rate(node.get_parameter("hz", 50.0)):
        ax = ROLLING * np.sin(np.radians(tilt_y))
        ay = -ROLLING * np.sin(np.radians(tilt_x))
        vx, vy = vx + ax * DT, vy + ay * DT
        x, y = x + vx * DT, y + vy * DT
        worst = max(worst, abs(x), abs(y))
        if max(abs(x), abs(y)) > HALF_PLATE:
            raise RuntimeError(f"the ball fell off the plate at t={step * DT:.2f} s ({x:.3f}, {y:.3f})")
        distance = float(np.hypot(x, y))
        if distance < 0.01 and settled_at is None:
            settled_at = step * DT
        elif distance >= 0.01:
            settled_at = None
        pub.publish(BallState(t=step * DT, x=float(x), y=float(y), vx=float(vx), vy=float(vy)))
        if step + 1 >= steps:
            break
        # lockstep: the plate pose answering this state acts during the next step, so the
        # result depends on the computation only, not on how fast the chain was mapped
        latest = pose.take(timeout=1.0)
        tilt_x, tilt_y = latest.x, latest.y
    node.log.info("after %.1f s: ball at (%.4f, %.4f) m, %.4f m from the centre; farthest %.4f m; settled at %s",
                  steps * DT, x, y, float(np.hypot(x, y)), worst,
                  "never" if settled_at is None else f"{settled_at:.2f} s")


def touch(node: Node) -> None:
    pub = node.create_publisher(Point, "ball_position")
    rng = np.random.default_rng(11)
    noise = node.get_parameter("noise_m", 0.002)
    for state in node.create_subscription(BallState, "ball_state"):
        pub.publish(Point(x=state.x + rng.normal(0, noise), y=state.y + rng.normal(0, noise)))


class Kalman:
    """Constant-velocity Kalman filter for one axis."""

    def __init__(self, noise: float) -> None:
        self.state = np.zeros(2)
        self.cov = np.eye(2)
        self.f = np.array([[1.0, DT], [0.0, 1.0]])
        self.q = np.array([[DT**4 / 4, DT**3 / 2], [DT**3 / 2, DT**2]]) * 0.5**2
        self.r = noise**2

    def update(self, measured: float) -> np.ndarray:
        self.state = self.f @ self.state
        self.cov = self.f @ self.cov @ self.f.T + self.q
        gain = self.cov[:, 0] / (self.cov[0, 0] + self.r)
        self.state = self.state + gain * (measured - self.state[0])
        self.cov = self.cov - np.outer(gain, self.cov[0])
        return self.state


def control(node: Node) -> None:
    pub = node.create_publisher(UInt32, "platform_angles")
    noise = node.get_parameter("noise_m", 0.002)
    filters = [Kalman(noise), Kalman(noise)]
    kp, ki, kd = node.get_parameter("kp", 1.3), node.get_parameter("ki", 0.1), node.get_parameter("kd", 0.7)
    integral = np.zeros(2)
    arrivals: list[float] = []
    try:
        for measured in node.create_subscription(Point, "ball_position"):
            arrivals.append(time.monotonic())
            (px, vx), (py, vy) = filters[0].update(measured.x), filters[1].update(measured.y)
            integral += np.array([px, py]) * DT
            push_x = kp * px + ki * integral[0] + kd * vx
            push_y = kp * py + ki * integral[1] + kd * vy
            tilt_y = np.clip(-np.degrees(push_x), -MAX_TILT_DEG, MAX_TILT_DEG)
            tilt_x = np.clip(np.degrees(push_y), -MAX_TILT_DEG, MAX_TILT_DEG)
            pub.publish(UInt32(data=pack(float(tilt_x), float(tilt_y))))
    finally:
        if len(arrivals) > 2:
            periods = np.diff(arrivals) * 1000.0
            node.log.info("control period %.2f ± %.2f ms (min %.2f, max %.2f) over %d cycles",
                          periods.mean(), periods.std(), periods.min(), periods.max(), periods.size)


def inverse(node: Node) -> None:
    pub = node.create_publisher(ServoPwm, "servo_pwm")
    for msg in node.create_subscription(UInt32, "platform_angles"):
        x, y = unpack(msg.data)
        pub.publish(ServoPwm(command=msg.data, pwm=to_pwm(servo_angles(x, y))))


def forward(pwm: np.ndarray, guess: np.ndarray) -> np.ndarray:
    """The tilt whose servo angles best match ``pwm`` (Gauss-Newton on the inverse kinematics)."""
    target = np.radians(pwm.astype(np.float64) / 1023.0 * 180.0 - 90.0)
    tilt = guess.copy()
    for _ in range(6):
        residual = servo_angles(*tilt) - target
        jacobian = np.stack([(servo_angles(*(tilt + d)) - servo_angles(*(tilt - d))) / 0.02
                             for d in (np.array([0.01, 0.0]), np.array([0.0, 0.01]))], axis=1)
        tilt = tilt - np.linalg.lstsq(jacobian, residual, rcond=None)[0]
    return tilt


def servo(node: Node) -> None:
    pub = node.create_publisher(Vector3, "platform_pose")
    tilt = np.zeros(2)
    for msg in node.create_subscription(ServoPwm, "servo_pwm"):
        tilt = forward(msg.pwm, tilt)
        pub.publish(Vector3(x=float(tilt[0]), y=float(tilt[1])))
