"""Inverse kinematics of the ball-on-plate station's rotary-servo Stewart platform.

Geometry (metres): six base joints on a circle of radius R_BASE, six platform joints
on a circle of radius R_PLATFORM, servo arms of length ARM, rods of length ROD. The
platform's home height is where every arm is horizontal. A command is two rotation
angles (about x, then y) in degrees, each a signed Q8.6 fixed-point number (1/64
degree) in one half of a uint32: x in the low 16 bits, y in the high 16 bits.
"""

import numpy as np

R_BASE = 0.070
R_PLATFORM = 0.050
ARM = 0.020
ROD = 0.110
_BASE_DEG = np.array([-8.0, 8.0, 112.0, 128.0, 232.0, 248.0])
_PLATFORM_DEG = np.array([-25.0, 25.0, 95.0, 145.0, 215.0, 265.0])
_SIDE = np.array([-1.0, 1.0, -1.0, 1.0, -1.0, 1.0])

BASE = np.stack([R_BASE * np.cos(np.radians(_BASE_DEG)), R_BASE * np.sin(np.radians(_BASE_DEG)), np.zeros(6)], 1)
PLATFORM = np.stack([R_PLATFORM * np.cos(np.radians(_PLATFORM_DEG)),
                     R_PLATFORM * np.sin(np.radians(_PLATFORM_DEG)), np.zeros(6)], 1)
BETA = np.radians(_BASE_DEG) + _SIDE * np.pi / 2  # direction of each servo arm in the base plane
_ARM_TIPS = BASE[:, :2] + ARM * np.stack([np.cos(BETA), np.sin(BETA)], 1)
HOME = float(np.sqrt(ROD**2 - ((PLATFORM[:, :2] - _ARM_TIPS) ** 2).sum(1)).mean())


def pack(x_deg: float, y_deg: float) -> int:
    """Two angles as signed Q8.6 halves of one uint32."""
    qx, qy = (round(v * 64) & 0xFFFF for v in (x_deg, y_deg))
    return qx | (qy << 16)


def unpack(command: int) -> tuple[float, float]:
    halves = np.array([command & 0xFFFF, (command >> 16) & 0xFFFF], dtype=np.uint16).view(np.int16)
    return float(halves[0]) / 64.0, float(halves[1]) / 64.0


def rotation(x_deg: float, y_deg: float) -> np.ndarray:
    cx, sx = np.cos(np.radians(x_deg)), np.sin(np.radians(x_deg))
    cy, sy = np.cos(np.radians(y_deg)), np.sin(np.radians(y_deg))
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    both: np.ndarray = ry @ rx
    return both


def platform_joints(x_deg: float, y_deg: float) -> np.ndarray:
    joints: np.ndarray = PLATFORM @ rotation(x_deg, y_deg).T + np.array([0.0, 0.0, HOME])
    return joints


def servo_angles(x_deg: float, y_deg: float) -> np.ndarray:
    """The six arm angles (radians) that put the platform at the given tilt, in closed form."""
    leg = platform_joints(x_deg, y_deg) - BASE
    big_l = (leg**2).sum(1) - (ROD**2 - ARM**2)
    big_m = 2 * ARM * leg[:, 2]
    big_n = 2 * ARM * (np.cos(BETA) * leg[:, 0] + np.sin(BETA) * leg[:, 1])
    angles: np.ndarray = np.arcsin(big_l / np.hypot(big_m, big_n)) - np.arctan2(big_n, big_m)
    return angles


def to_pwm(angles: np.ndarray) -> np.ndarray:
    """-90..+90 degrees onto 0..1023 (10 bits)."""
    pwm: np.ndarray = np.clip(np.round((np.degrees(angles) + 90.0) / 180.0 * 1023.0), 0, 1023).astype(np.uint16)
    return pwm
