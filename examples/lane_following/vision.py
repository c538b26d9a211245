"""The scene and the image processing of the lane-following vehicle (fpgaDDS Fig. 6).

Bird's-eye view (BEV): 1000 x 600 pixels of 1 cm; column 500 is straight ahead, row 599 is
1 m in front of the car, row 0 is 7 m. The camera (640 x 480) sees the BEV ground plane
through a fixed homography; everything is vectorised numpy.
"""

import numpy as np

from hetros.hw.reference import Compensation, gaussian_blur

CAM_W, CAM_H = 640, 480
BEV_W, BEV_H = 1000, 600
HORIZON = 200
LANE_HALF_WIDTH_M = 1.0
STRIPE_M = 0.12
NEAR_ROW = 560

# BEV corners (x, y) -> camera trapezoid: the near edge spans the image, the far edge narrows.
_BEV_CORNERS = np.array([[0, 0], [BEV_W - 1, 0], [BEV_W - 1, BEV_H - 1], [0, BEV_H - 1]], dtype=np.float64)
_CAM_CORNERS = np.array([[250, HORIZON + 20], [390, HORIZON + 20], [CAM_W + 260, CAM_H - 1], [-260, CAM_H - 1]],
                        dtype=np.float64)


def homography(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    rows = []
    for (x, y), (u, v) in zip(src, dst, strict=True):
        rows.append([x, y, 1, 0, 0, 0, -u * x, -u * y, -u])
        rows.append([0, 0, 0, x, y, 1, -v * x, -v * y, -v])
    _, _, vt = np.linalg.svd(np.array(rows))
    homography: np.ndarray = vt[-1].reshape(3, 3) / vt[-1, -1]
    return homography


BEV_TO_CAM = homography(_BEV_CORNERS, _CAM_CORNERS)
CAM_TO_BEV = np.linalg.inv(BEV_TO_CAM)


def apply(h: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    w = h[2, 0] * x + h[2, 1] * y + h[2, 2]
    return (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / w, (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / w


def lane_shape(frame: int) -> tuple[float, float]:
    """Lateral offset (m) and curvature (1/m^2 factor) of the lane centre for a frame."""
    return 0.35 * np.sin(frame / 9.0), 0.02 * np.sin(frame / 13.0)


def centre_m(frame: int, forward_m: np.ndarray) -> np.ndarray:
    offset, curve = lane_shape(frame)
    return offset + curve * forward_m**2


def forward_of_row(row: np.ndarray) -> np.ndarray:
    return 1.0 + (BEV_H - 1 - row) / 100.0


def light_is_red(frame: int) -> bool:
    return 20 <= frame % 60 < 35


def render(frame: int) -> tuple[np.ndarray, float]:
    """A camera frame (noise and outlier pixels included) and the true lane centre at NEAR_ROW (BEV px)."""
    rng = np.random.default_rng(frame)
    img = np.empty((CAM_H, CAM_W, 3), dtype=np.float64)
    img[:HORIZON] = (135, 170, 215)
    img[HORIZON:] = (70, 70, 72)
    v, u = np.mgrid[HORIZON:CAM_H, 0:CAM_W].astype(np.float64)
    bx, by = apply(CAM_TO_BEV, u, v)
    lateral = (bx - BEV_W / 2) / 100.0
    centre = centre_m(frame, forward_of_row(by))
    on_road = (by >= 0) & (by < BEV_H)
    stripe = np.zeros_like(on_road)
    for side in (-1, 1):
        stripe |= np.abs(lateral - (centre + side * LANE_HALF_WIDTH_M)) < STRIPE_M / 2
    img[HORIZON:][stripe & on_road] = (235, 235, 235)
    light = (255, 20, 20) if light_is_red(frame) else (20, 230, 40)
    cy, cx = 60, 560
    yy, xx = np.mgrid[0:CAM_H, 0:CAM_W]
    img[(yy - cy) ** 2 + (xx - cx) ** 2 < 15**2] = light
    img += rng.normal(0, 6, img.shape)
    outliers = rng.random((CAM_H, CAM_W)) < 0.004
    img[outliers] = rng.choice([0, 255], size=(int(outliers.sum()), 1))
    truth = BEV_W / 2 + 100.0 * float(centre_m(frame, forward_of_row(np.array(NEAR_ROW))))
    return np.clip(img, 0, 255).astype(np.uint8), truth


# The image stages are the ones hetros.hw.nodes implements in hardware, so an fpga mapping of the
# vehicle (project_fpga.yaml) computes what this one does, bit for bit: the compensation (a 3x3 median
# of each channel, then a contrast stretch from the previous frame's 1st-99th percentile) and a 3x3
# Gaussian blur, both integer, borders 0.
compensate = Compensation  # a class: one instance per stream of frames (it keeps the percentiles)
blur = gaussian_blur


_BY, _BX = np.mgrid[0:BEV_H, 0:BEV_W].astype(np.float64)
_SRC_U, _SRC_V = apply(BEV_TO_CAM, _BX, _BY)
_VALID = (_SRC_U >= 0) & (_SRC_U < CAM_W) & (_SRC_V >= 0) & (_SRC_V < CAM_H)
_U = np.clip(np.round(_SRC_U), 0, CAM_W - 1).astype(np.intp)
_V = np.clip(np.round(_SRC_V), 0, CAM_H - 1).astype(np.intp)
# The warp reads camera rows _TOP and below only. Each bird's-eye pixel is one look-up into those rows'
# grey values laid out flat, with one 0 after them that the pixels outside the camera's view read.
_TOP = int(_V[_VALID].min())
_BAND = (CAM_H - _TOP) * CAM_W
_LOOKUP = np.where(_VALID, (_V - _TOP) * CAM_W + _U, _BAND).astype(np.int32)


def project(img: np.ndarray) -> np.ndarray:
    """Perspective warp to the 1000 x 600 bird's-eye view (grey: the channels' mean, rounded down).

    In integers (a sum of three bytes fits 16 bits) and one ``np.take``: 14x faster than the float mean
    and a masked two-dimensional gather it replaced, and the same bytes (``project_reference``)."""
    band = img[_TOP:]
    total = band[..., 0].astype(np.uint16)
    total += band[..., 1]
    total += band[..., 2]
    grey = np.zeros(_BAND + 1, np.uint8)
    np.floor_divide(total, 3, out=total)
    grey[:_BAND] = total.reshape(-1)
    return np.take(grey, _LOOKUP)


def project_reference(img: np.ndarray) -> np.ndarray:
    """The warp as written first (float mean, masked gather): what ``project`` is held to."""
    grey = img.mean(axis=2).astype(np.uint8)
    return np.where(_VALID, grey[_V, _U], 0).astype(np.uint8)


def find_lane(bev: np.ndarray) -> tuple[bool, float, float, float]:
    """Left and right stripe near the car (bright columns of a band around NEAR_ROW), and their centre."""
    band = bev[NEAR_ROW - 10:NEAR_ROW + 10]
    bright = (band > 180).sum(axis=0)
    columns = np.flatnonzero(bright > 10)
    if columns.size < 2:
        return False, 0.0, 0.0, 0.0
    gaps = np.flatnonzero(np.diff(columns) > 20)
    if gaps.size == 0:
        return False, 0.0, 0.0, 0.0
    left = float(columns[: gaps[0] + 1].mean())
    right = float(columns[gaps[-1] + 1:].mean())
    return True, (left + right) / 2.0, left, right


def light_pixels(img: np.ndarray, colour: str) -> int:
    """Pixels of the traffic-light colour in the upper part of the frame, thresholded in HSV.

    Only a pixel whose brightest channel exceeds half (8 bits: 128 or more) and whose spread is
    well over half of it can be vivid, and those are few: the HSV arithmetic (float32, as before)
    runs on them alone. The integer test is looser than the float one, so no vivid pixel is lost.
    """
    upper = img[:HORIZON]
    red, green, blue = upper[..., 0], upper[..., 1], upper[..., 2]
    brightest = np.maximum(np.maximum(red, green), blue).astype(np.int16)
    spread = brightest - np.minimum(np.minimum(red, green), blue)
    candidates = upper[(brightest >= 128) & (5 * spread >= 3 * brightest - 5)]
    rgb = candidates.astype(np.float32) / 255.0
    maxc, minc = rgb.max(axis=1), rgb.min(axis=1)
    delta = np.where(maxc > minc, maxc - minc, 1.0)
    r, g, b = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    hue = np.where(maxc == r, ((g - b) / delta) % 6, np.where(maxc == g, (b - r) / delta + 2, (r - g) / delta + 4)) * 60
    saturation = np.where(maxc > 0, (maxc - minc) / np.maximum(maxc, 1e-6), 0)
    vivid = (saturation > 0.6) & (maxc > 0.5)
    if colour == "red":
        return int((vivid & ((hue < 15) | (hue > 345))).sum())
    return int((vivid & (hue > 90) & (hue < 150)).sum())
