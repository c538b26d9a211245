"""A small CNN in numpy: 3 x (3x3 convolution + ReLU + 2x2 max pooling), then 2 fully connected
layers. Inference is what the service runs; training (``train.py``) uses the same forward pass
and the backward pass below. Images are 8x8 (scikit-learn's handwritten digits).
"""

from pathlib import Path
from typing import Any

import numpy as np

WEIGHTS = Path(__file__).with_name("weights.npz")
CHANNELS = (1, 8, 16, 32)


def im2col(x: np.ndarray) -> np.ndarray:
    """(N, H, W, C) with 'same' zero padding -> (N, H, W, 9*C) patches of 3x3."""
    _n, h, w, _c = x.shape
    padded = np.pad(x, ((0, 0), (1, 1), (1, 1), (0, 0)))
    patches = [padded[:, i:i + h, j:j + w, :] for i in range(3) for j in range(3)]
    return np.concatenate(patches, axis=3)


def col2im(cols: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    n, h, w, c = shape
    padded = np.zeros((n, h + 2, w + 2, c))
    for k, (i, j) in enumerate((i, j) for i in range(3) for j in range(3)):
        padded[:, i:i + h, j:j + w, :] += cols[..., k * c:(k + 1) * c]
    return padded[:, 1:-1, 1:-1, :]


def pool(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n, h, w, c = x.shape
    blocks = x.reshape(n, h // 2, 2, w // 2, 2, c)
    out = blocks.max(axis=(2, 4))
    mask = blocks == out[:, :, None, :, None, :]
    return out, mask


def forward(params: dict[str, np.ndarray], images: np.ndarray, keep: list[tuple[Any, ...]] | None = None
            ) -> np.ndarray:
    """Class scores (logits) for (N, 8, 8) images scaled to 0..1."""
    x = images[..., None]
    for layer in range(3):
        cols = im2col(x)
        z = cols @ params[f"conv{layer}"] + params[f"bconv{layer}"]
        a = np.maximum(z, 0)
        pooled, mask = pool(a)
        if keep is not None:
            keep.append((cols, x.shape, z, mask, a.shape))
        x = pooled
    flat = x.reshape(len(x), -1)
    hidden = np.maximum(flat @ params["fc0"] + params["bfc0"], 0)
    if keep is not None:
        keep.append((flat, hidden))
    logits: np.ndarray = hidden @ params["fc1"] + params["bfc1"]
    return logits


def init(rng: np.random.Generator) -> dict[str, np.ndarray]:
    params = {}
    for layer in range(3):
        fan_in = 9 * CHANNELS[layer]
        params[f"conv{layer}"] = rng.normal(0, np.sqrt(2 / fan_in), (fan_in, CHANNELS[layer + 1]))
        params[f"bconv{layer}"] = np.zeros(CHANNELS[layer + 1])
    params["fc0"] = rng.normal(0, np.sqrt(2 / 32), (32, 64))
    params["bfc0"] = np.zeros(64)
    params["fc1"] = rng.normal(0, np.sqrt(2 / 64), (64, 10))
    params["bfc1"] = np.zeros(10)
    return params


def gradients(params: dict[str, np.ndarray], images: np.ndarray, labels: np.ndarray
              ) -> tuple[float, dict[str, np.ndarray]]:
    keep: list[tuple[Any, ...]] = []  # what forward kept per layer, for the backward pass
    logits = forward(params, images, keep)
    shifted = logits - logits.max(1, keepdims=True)
    probs = np.exp(shifted) / np.exp(shifted).sum(1, keepdims=True)
    n = len(images)
    loss = float(-np.log(probs[np.arange(n), labels] + 1e-12).mean())
    grad = probs
    grad[np.arange(n), labels] -= 1
    grad /= n
    flat, hidden = keep.pop()
    g = {"fc1": hidden.T @ grad, "bfc1": grad.sum(0)}
    dh = (grad @ params["fc1"].T) * (hidden > 0)
    g["fc0"], g["bfc0"] = flat.T @ dh, dh.sum(0)
    dx = (dh @ params["fc0"].T).reshape(n, 1, 1, CHANNELS[3])
    for layer in (2, 1, 0):
        cols, in_shape, z, mask, a_shape = keep.pop()
        _nn, _h, _w, c = a_shape
        da = (mask * dx[:, :, None, :, None, :]).reshape(a_shape)
        dz = da * (z > 0)
        g[f"conv{layer}"] = cols.reshape(-1, cols.shape[-1]).T @ dz.reshape(-1, c)
        g[f"bconv{layer}"] = dz.sum((0, 1, 2))
        dx = col2im(dz @ params[f"conv{layer}"].T, in_shape)
    return loss, g


def load() -> dict[str, np.ndarray]:
    with np.load(WEIGHTS) as data:
        return {k: data[k].astype(np.float32) for k in data.files}


def classify(params: dict[str, np.ndarray], pixels: np.ndarray) -> np.ndarray:
    """Scores for one 8x8 image of 0..16 values."""
    scores: np.ndarray = forward(params, (pixels.reshape(1, 8, 8).astype(np.float32) / 16.0))[0]
    return scores
