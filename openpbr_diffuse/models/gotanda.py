"""Gotanda 2012, "Beyond a simple physically based Blinn-Phong model", Eq. 20-25.

Eq. 25 (the "improved" model) in the shininess parameterisation of Eq. 21
(sigma = sqrt(2/shininess)):

  L_r = rho/pi E0 [ mu_i (1 - 1/(2 + 0.65 shi)) + 1/(2.22222 + 0.1 shi) s min(1, mu_i/mu_o) ]  (s >= 0)
  L_r = rho/pi E0 [ mu_i (1 - 1/(2 + 0.65 shi)) + 1/(2.22222 + 0.1 shi) s mu_i ]             (s < 0)

Dividing by mu_i and substituting shi = 2/sigma^2 gives f = rho/pi (A + B s/t) with FON's t
and A = 1 - 0.5 s2/(s2 + 0.65), B = 0.45 s2/(s2 + 0.09) (2.22222 is 1/0.45 rounded in
the notes; this uses 1/0.45).  It is an approximation of full Oren-Nayar, graded, not a
reference.
"""

from .._jit import INV_PI, kernel
from .fon import fon_shape_albedo, fon_shape_average, s_over_t


@kernel
def gotanda_AB(sigma: float) -> tuple[float, float]:
    s2 = sigma * sigma
    return 1.0 - 0.5 * s2 / (s2 + 0.65), 0.45 * s2 / (s2 + 0.09)


@kernel
def gotanda_terms(mu_i: float, mu_o: float, s: float, sigma: float) -> float:
    """f / rho of Eq. 25."""
    A, B = gotanda_AB(sigma)
    return (A + B * s_over_t(mu_i, mu_o, s)) * INV_PI


@kernel
def gotanda_albedo(mu: float, sigma: float, average: bool) -> float:
    """E(mu) / rho (or <E> / rho): the lobe has FON's shape, E = A + B G_F/pi (Eq. 12-13, 15)."""
    A, B = gotanda_AB(sigma)
    if average:
        return fon_shape_average(A, B)
    return fon_shape_albedo(mu, A, B)
