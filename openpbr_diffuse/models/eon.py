"""EON: energy-preserving Oren-Nayar, EON paper Eq. 16-20 and Listing 1.

f_EON = f_FON + f_ms with

- rho_ms = rho^2 <E_F> / (1 - rho (1 - <E_F>))                       (Eq. 18)
- f_ms = rho_ms/pi * max(eps, 1 - E_F(mu_o)) max(eps, 1 - E_F(mu_i))
  / max(eps, 1 - <E_F>)                                               (Eq. 17, Listing 1)
- E_EON(mu) = rho E_F(mu) + rho_ms (1 - E_F(mu))                      (Eq. 20)

"eon" uses the exact E_F (Eq. 12), "eon_approx" the Eq. 14 fit inside f_ms; the
single-scattering FON term is the same in both.
"""

from typing import Any

from .._jit import EPS, INV_PI, kernel
from .fon import E_F, E_F_avg, E_F_avg_of, FloatOrArray, fon_A, fon_shape_albedo, fon_terms


@kernel
def rho_ms(rho: FloatOrArray, avg: FloatOrArray) -> Any:
    """Multiple-scattering albedo rho_ms (Eq. 18) for <E_F> = ``avg``."""
    return rho * rho * avg / (1.0 - rho * (1.0 - avg))


@kernel
def eon_terms(mu_i: float, mu_o: float, s: float, r: float, approx: bool) -> tuple[float, float, float]:
    """Return (g, h, <E_F>) with f_EON = rho g + rho_ms(rho, <E_F>) h."""
    avg = E_F_avg(r)
    g = fon_terms(mu_i, mu_o, s, r)
    h = max(EPS, 1.0 - E_F(mu_o, r, approx)) * max(EPS, 1.0 - E_F(mu_i, r, approx)) / max(EPS, 1.0 - avg) * INV_PI
    return g, h, avg


@kernel
def eon_albedo_fit(r: float) -> tuple[float, float, float]:
    """(A_F, B_F = r A_F, s_h): the part of the exact E_EON(mu) (Eq. 20) that depends on r
    alone, for ``eon_albedo_at`` (once per material when r is fixed): E_F = A_F + B_F G_F/pi
    (Eq. 12-13) and e_h = max(eps, 1 - E_F) s_h, s_h = (1 - <E_F>) / max(eps, 1 - <E_F>)."""
    A = fon_A(r)
    avg = E_F_avg(r)
    return A, r * A, (1.0 - avg) / max(EPS, 1.0 - avg)


@kernel
def eon_albedo_at(mu: float, A: float, B: float, s_h: float) -> tuple[float, float]:
    """(e_g, e_h) of E_EON(mu) = rho e_g + rho_ms e_h (Eq. 20) from ``eon_albedo_fit``."""
    e = fon_shape_albedo(mu, A, B)
    return e, max(EPS, 1.0 - e) * s_h


@kernel
def eon_albedo_terms(mu: float, r: float, approx: bool) -> tuple[float, float, float]:
    """Return (e_g, e_h, <E_F>) with E_EON(mu) = rho e_g + rho_ms e_h.

    e_g = E_F(mu) is the albedo of the FON term.  Integrating f_ms over the hemisphere
    gives (1 - E(mu)) (1 - <E>) / (1 - <E_F>) where E is the E_F variant used in f_ms:
    for "eon" that is Eq. 20 exactly; for "eon_approx" the cosine-weighted mean of the
    Eq. 14 fit is not exactly <E_F>, and this is the exact albedo of that lobe (it
    differs from Eq. 20 by < 5e-4).  The eps guards change it by < 1e-7; for "eon_approx"
    the guard max(eps, 1 - E_F(mu_i)) is also active for mu_i < 1.39e-3, where the Eq. 14
    fit exceeds 1, which this closed form ignores (4e-10, resolved in the reference tables).
    """
    avg = E_F_avg(r)
    if not approx:
        A, B, s_h = eon_albedo_fit(r)
        e_g, e_h = eon_albedo_at(mu, A, B, s_h)
        return e_g, e_h, avg
    e_h = max(EPS, 1.0 - E_F(mu, r, approx)) * (1.0 - E_F_avg_of(r, approx)) / max(EPS, 1.0 - avg)
    return E_F(mu, r, False), e_h, avg


@kernel
def eon_average_terms(r: float, approx: bool) -> tuple[float, float, float]:
    """Return (<e_g>, <e_h>, <E_F>) of the average albedo <E_EON> = rho <e_g> + rho_ms <e_h>."""
    avg = E_F_avg(r)
    avg_used = E_F_avg_of(r, approx)
    return avg, (1.0 - avg_used) * (1.0 - avg_used) / max(EPS, 1.0 - avg), avg
