"""Train the classifier on scikit-learn's handwritten digits; writes weights.npz (small, committed).

    python examples/digit_classifier/train.py

The held-out split (seed 0, 25 %) is the one the integration test queries through the service.
"""

from typing import Any

import numpy as np
from cnn import WEIGHTS, forward, gradients, init

try:
    from sklearn.datasets import load_digits  # type: ignore[import-untyped]
    from sklearn.model_selection import train_test_split  # type: ignore[import-untyped]
except ImportError as exc:
    raise ImportError("the digit classifier takes its digits from scikit-learn: "
                      "run `.venv/bin/pip install -e '.[examples]'` (or `make install-examples`)") from exc


def split() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    digits = load_digits()
    train_x, test_x, train_y, test_y = train_test_split(digits.images, digits.target, test_size=0.25, random_state=0,
                                                        stratify=digits.target)
    return np.asarray(train_x), np.asarray(test_x), np.asarray(train_y), np.asarray(test_y)


def main() -> None:
    train_x, test_x, train_y, test_y = split()
    rng = np.random.default_rng(0)
    params = init(rng)
    moments = {k: (np.zeros_like(v), np.zeros_like(v)) for k, v in params.items()}
    step = 0
    epochs = 80
    for epoch in range(epochs):
        rate = 0.003 * 0.5 * (1 + np.cos(np.pi * epoch / epochs))  # cosine decay: a stable end point
        order = rng.permutation(len(train_x))
        for start in range(0, len(order), 32):
            batch = order[start:start + 32]
            images = train_x[batch] / 16.0
            shift = rng.integers(-1, 2, 2)
            images = np.roll(images, tuple(shift), axis=(1, 2))
            loss, grads = gradients(params, images, train_y[batch])
            step += 1
            for key, grad in grads.items():
                m, v = moments[key]
                m[:] = 0.9 * m + 0.1 * grad
                v[:] = 0.999 * v + 0.001 * grad**2
                params[key] -= rate * (m / (1 - 0.9**step)) / (np.sqrt(v / (1 - 0.999**step)) + 1e-8)
        accuracy = (forward(params, test_x / 16.0).argmax(1) == test_y).mean()
        print(f"epoch {epoch:2d} loss {loss:.3f} held-out accuracy {accuracy:.4f}")
    arrays: dict[str, Any] = {k: v.astype(np.float32) for k, v in params.items()}
    np.savez(WEIGHTS, **arrays)
    print(f"wrote {WEIGHTS}")


if __name__ == "__main__":
    main()
