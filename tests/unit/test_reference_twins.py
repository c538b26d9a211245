"""The fast software twins of the reference hardware nodes, held to the direct formulas.

``hetros.hw.reference`` computes the median as a network on 8-bit buffers, the blur separably in
16 bits and the stretch through a table: these are the plain definitions they must equal, value
for value, on random and on extreme images of every shape the nodes take.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from hetros.hw.reference import Compensation, gaussian_blur, median3x3


def _windows(image: np.ndarray[Any, Any]) -> list[np.ndarray[Any, Any]]:
    x = image.astype(np.int32)
    rows, columns = x.shape[0] - 2, x.shape[1] - 2
    return [x[r:r + rows, c:c + columns] for r in range(3) for c in range(3)]


def slow_median(image: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    out = np.zeros(image.shape, np.uint8)
    if image.shape[0] >= 3 and image.shape[1] >= 3:
        out[1:-1, 1:-1] = np.median(np.stack(_windows(image)), axis=0).astype(np.uint8)
    return out


def slow_blur(image: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    out = np.zeros(image.shape, np.uint8)
    if image.shape[0] >= 3 and image.shape[1] >= 3:
        t0, t1, t2, m0, m1, m2, b0, b1, b2 = _windows(image)
        out[1:-1, 1:-1] = (t0 + 2 * t1 + t2 + 2 * (m0 + 2 * m1 + m2) + b0 + 2 * b1 + b2 + 8) >> 4
    return out


def slow_stretch(median: np.ndarray[Any, Any], low: int, high: int) -> np.ndarray[Any, Any]:
    above = np.maximum(median.astype(np.int32) - low, 0)
    return np.minimum(above * 255 // max(high - low, 1), 255).astype(np.uint8)


SHAPES = [(480, 640, 3), (48, 64), (3, 3), (3, 7, 3), (2, 9), (9, 2, 3), (17, 5)]


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("fill", ["random", "extremes", "constant"])
def test_the_twins_equal_the_direct_formulas(shape: tuple[int, ...], fill: str) -> None:
    rng = np.random.default_rng(len(shape) * 1000 + shape[0])
    if fill == "random":
        image = rng.integers(0, 256, shape, dtype=np.uint8)
    elif fill == "extremes":
        image = rng.choice(np.array([0, 1, 254, 255], np.uint8), shape)
    else:
        image = np.full(shape, 255, np.uint8)
    assert np.array_equal(median3x3(image), slow_median(image))
    assert np.array_equal(gaussian_blur(image), slow_blur(image))
    assert median3x3(image).dtype == gaussian_blur(image).dtype == np.uint8


def test_compensation_equals_the_direct_stretch_frame_after_frame() -> None:
    rng = np.random.default_rng(5)
    compensate = Compensation()
    low, high = 0, 255
    for _ in range(4):
        image = rng.integers(20, 200, (48, 64, 3), dtype=np.uint8)
        median = slow_median(image)
        assert np.array_equal(compensate(image), slow_stretch(median, low, high))
        counts = np.bincount(median.reshape(-1), minlength=256).cumsum()
        low = int(np.argmax(100 * counts >= counts[-1]))
        high = int(np.argmax(100 * counts >= 99 * counts[-1]))
        assert (compensate.low, compensate.high) == (low, high)
