"""Packing NumPy inputs into the float32 rows a wrapped kernel reads, and test directions."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def rows(*columns: ArrayLike, n: int | None = None) -> np.ndarray:
    """Stack columns ((n,) or (n,k) arrays, or scalars) side by side into an (n, K) float32 array.

    >>> rows(np.zeros((2, 3)), [0.5, 1.0], 7.0).tolist()
    [[0.0, 0.0, 0.0, 0.5, 7.0], [0.0, 0.0, 0.0, 1.0, 7.0]]
    """
    cols = [np.asarray(c, dtype=np.float64) for c in columns]
    if n is None:
        n = max((c.shape[0] for c in cols if c.ndim > 0), default=1)
    out = []
    for c in cols:
        c = np.broadcast_to(
            c if c.ndim != 1 or c.shape[0] != n else c[:, None], (n, 1) if c.ndim < 2 else (n, c.shape[-1])
        )
        out.append(c)
    return np.ascontiguousarray(np.concatenate(out, axis=1), dtype=np.float32)


def direction(mu: ArrayLike, phi: ArrayLike = 0.0) -> np.ndarray:
    """Unit vectors with z = mu at azimuth phi: (..., 3).

    >>> direction(0.6).round(6).tolist()
    [0.8, 0.0, 0.6]
    """
    mu = np.asarray(mu, dtype=np.float64)
    s = np.sqrt(np.clip(1.0 - mu * mu, 0.0, None))
    phi = np.broadcast_to(np.asarray(phi, dtype=np.float64), mu.shape)
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1)
