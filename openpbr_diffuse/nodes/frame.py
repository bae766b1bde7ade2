"""Local shading frames built from a world-space normal.

The lobe models and samplers work in a local frame with the normal +z.  A shading node
given a world-space ``normal`` (MaterialX ``normal`` / OpenPBR ``geometry_normal``)
builds an orthonormal tangent frame (t, b, n) from it and maps directions in and out.
Every node in this package is isotropic, so which tangent is chosen does not change any
value -- only the azimuth of the local coordinates -- and the branchless construction of
Duff et al. 2017 ("Building an orthonormal basis, revisited", JCGT 6(1), Listing 3) is
used: continuous except across n.z = 0 and exact in floating point up to rounding.
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray


class Frame:
    """Orthonormal frame (t, b, n); ``normal=None`` is the identity (local coordinates).

    Parameters
    ----------
    normal : ndarray (..., 3) or None
        Unit normals (validated by the caller).
    """

    t: NDArray[np.float64]
    b: NDArray[np.float64]

    def __init__(self, normal: ArrayLike | None = None) -> None:
        self.normal = None if normal is None else np.asarray(normal, dtype=np.float64)
        if self.normal is None:
            return
        n = self.normal
        x, y, z = n[..., 0], n[..., 1], n[..., 2]
        sign = np.where(z >= 0.0, 1.0, -1.0)
        a = -1.0 / (sign + z)
        b = x * y * a
        self.t = np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=-1)
        self.b = np.stack([b, sign + y * y * a, -y], axis=-1)

    @property
    def is_local(self) -> bool:
        return self.normal is None

    def to_local(self, w: NDArray[np.float64]) -> NDArray[np.float64]:
        """World directions (..., 3) -> local (..., 3) = (w.t, w.b, w.n)."""
        if self.normal is None:
            return w
        return np.stack(
            [
                np.einsum("...k,...k->...", w, self.t),
                np.einsum("...k,...k->...", w, self.b),
                np.einsum("...k,...k->...", w, self.normal),
            ],
            axis=-1,
        )

    def to_world(self, w: NDArray[np.float64]) -> NDArray[np.float64]:
        """Local directions (..., 3) -> world: x t + y b + z n."""
        if self.normal is None:
            return w
        return w[..., 0:1] * self.t + w[..., 1:2] * self.b + w[..., 2:3] * self.normal
