"""The software twins of the reference hardware nodes: numpy, bit-exact, no Amaranth.

Each function is what a hardware node in ``hetros.hw.nodes`` computes, and what a node's
Python implementation calls, so one node has two implementations with the same results
(the tests hold the hardware to these). Border pixels (outer rows and columns) are 0.
"""

from __future__ import annotations

from typing import Any

import numpy as np

Image = np.ndarray[Any, np.dtype[np.uint8]]


def _windows(image: np.ndarray[Any, Any]) -> tuple[np.ndarray[Any, Any], ...]:
    """The nine shifted views of a 3x3 window over the interior, top-left first, as int32."""
    x = image.astype(np.int32)
    rows, columns = x.shape[0] - 2, x.shape[1] - 2
    return tuple(x[r:r + rows, c:c + columns] for r in range(3) for c in range(3))


def sobel(image: np.ndarray[Any, Any]) -> Image:
    """Edges of a mono8 image: ``min(|Gx| + |Gy|, 255)`` with the 3x3 Sobel kernels."""
    out = np.zeros(image.shape, np.uint8)
    if image.shape[0] >= 3 and image.shape[1] >= 3:
        t0, t1, t2, m0, _m1, m2, b0, b1, b2 = _windows(image)
        gx = (t2 + 2 * m2 + b2) - (t0 + 2 * m0 + b0)
        gy = (b0 + 2 * b1 + b2) - (t0 + 2 * t1 + t2)
        out[1:-1, 1:-1] = np.minimum(np.abs(gx) + np.abs(gy), 255)
    return out


def gaussian_blur(image: np.ndarray[Any, Any]) -> Image:
    """A mono8 image through the 3x3 Gaussian ``[1 2 1; 2 4 2; 1 2 1] / 16``, rounded half up.

    Separably, in 16 bits (a sum is at most 16 * 255): the same integers as the 2-D kernel, with a
    quarter of the memory traffic of 32-bit windows (``tests/unit/test_reference_twins.py`` holds
    it to the direct formula).
    """
    out = np.zeros(image.shape, np.uint8)
    if image.shape[0] >= 3 and image.shape[1] >= 3:
        x = image.astype(np.uint16)
        columns = x[:-2] + x[1:-1] + x[1:-1] + x[2:]
        total = columns[:, :-2] + columns[:, 1:-1] + columns[:, 1:-1] + columns[:, 2:]
        total += 8
        total >>= 4
        out[1:-1, 1:-1] = total
    return out


_MEDIAN9 = ((1, 2), (4, 5), (7, 8), (0, 1), (3, 4), (6, 7), (1, 2), (4, 5), (7, 8), (0, 3), (5, 8), (4, 7),
            (3, 6), (1, 4), (2, 5), (4, 7), (4, 2), (6, 4), (4, 2))


def median3x3(image: np.ndarray[Any, Any]) -> Image:
    """The median of each pixel's 3x3 window, channel by channel (Paeth's network), borders 0.

    The network's compare-exchanges run on 8-bit views and a small pool of buffers that are reused
    (a fresh array per step page-faulted a megabyte each time): 38 passes of SIMD min/max.
    """
    out = np.zeros(image.shape, np.uint8)
    if image.shape[0] >= 3 and image.shape[1] >= 3:
        pixels = np.ascontiguousarray(image, dtype=np.uint8)
        rows, columns = pixels.shape[0] - 2, pixels.shape[1] - 2
        values = [pixels[r:r + rows, c:c + columns] for r in range(3) for c in range(3)]
        shape = values[0].shape
        pool = [np.empty(shape, np.uint8) for _ in range(2)]
        owned: set[int] = set()
        for a, b in _MEDIAN9:
            low, high = pool.pop(), pool.pop()
            np.minimum(values[a], values[b], out=low)
            np.maximum(values[a], values[b], out=high)
            for old in (values[a], values[b]):
                if id(old) in owned:
                    owned.discard(id(old))
                    pool.append(old)
            while len(pool) < 2:
                pool.append(np.empty(shape, np.uint8))
            values[a], values[b] = low, high
            owned.update((id(low), id(high)))
        out[1:-1, 1:-1] = values[4]
    return out


class Compensation:
    """The lane-following vehicle's image compensation, as ``hetros.hw.nodes.Compensation`` computes it: a
    3x3 median of each channel (borders 0), then a contrast stretch between the 1st and 99th percentile of
    the previous frame's median image (the first frame is not stretched). One instance per stream of
    frames: it keeps the percentiles from one frame to the next."""

    def __init__(self) -> None:
        self.low, self.high = 0, 255

    def __call__(self, image: np.ndarray[Any, Any]) -> Image:
        median = median3x3(image)
        # the stretch of each of the 256 values, then looked up: the same integers as per pixel, without a
        # division per pixel
        above = np.maximum(np.arange(256, dtype=np.int32) - self.low, 0)
        table = np.minimum(above * 255 // max(self.high - self.low, 1), 255).astype(np.uint8)
        stretched: Image = np.take(table, median)
        counts = np.bincount(median.reshape(-1), minlength=256).cumsum()
        total = int(counts[-1])
        self.low = int(np.argmax(100 * counts >= total))
        self.high = int(np.argmax(100 * counts >= 99 * total))
        return stretched
