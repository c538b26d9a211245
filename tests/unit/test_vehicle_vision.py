"""The lane-following vehicle's light detection and bird's-eye warp, fast, held to their direct formulas."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

FOLDER = Path(__file__).resolve().parents[2] / "examples" / "lane_following"


@pytest.fixture(scope="module")
def vision() -> Any:
    sys.path.insert(0, str(FOLDER))
    try:
        return importlib.import_module("vision")
    finally:
        sys.path.remove(str(FOLDER))


def direct(img: np.ndarray[Any, Any], colour: str, horizon: int) -> int:
    rgb = img[:horizon].astype(np.float32) / 255.0
    maxc, minc = rgb.max(axis=2), rgb.min(axis=2)
    delta = np.where(maxc > minc, maxc - minc, 1.0)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    hue = np.where(maxc == r, ((g - b) / delta) % 6, np.where(maxc == g, (b - r) / delta + 2, (r - g) / delta + 4)) * 60
    saturation = np.where(maxc > 0, (maxc - minc) / np.maximum(maxc, 1e-6), 0)
    vivid = (saturation > 0.6) & (maxc > 0.5)
    if colour == "red":
        return int((vivid & ((hue < 15) | (hue > 345))).sum())
    return int((vivid & (hue > 90) & (hue < 150)).sum())


def test_light_pixels_counts_what_the_direct_formula_counts(vision: Any) -> None:
    rng = np.random.default_rng(3)
    frames = [vision.render(frame)[0] for frame in range(0, 180, 9)]
    frames += [rng.integers(0, 256, (480, 640, 3), dtype=np.uint8) for _ in range(3)]
    frames.append(rng.choice(np.array([0, 76, 77, 127, 128, 129, 153, 254, 255], np.uint8), (480, 640, 3)))
    for image in frames:
        for colour in ("red", "green"):
            assert vision.light_pixels(image, colour) == direct(image, colour, vision.HORIZON)


def test_the_warp_gives_the_bytes_of_its_float_reference(vision: Any) -> None:
    rng = np.random.default_rng(4)
    frames = [vision.render(frame)[0] for frame in range(0, 180, 30)]
    frames += [rng.integers(0, 256, (480, 640, 3), dtype=np.uint8) for _ in range(2)]
    frames += [np.full((480, 640, 3), value, np.uint8) for value in (0, 1, 2, 254, 255)]
    for image in frames:
        warped = vision.project(image)
        assert warped.dtype == np.uint8 and warped.shape == (vision.BEV_H, vision.BEV_W)
        assert np.array_equal(warped, vision.project_reference(image))
