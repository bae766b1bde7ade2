"""The EON sampler: CLTC plus uniform hemisphere, one-sample MIS (Section 3.1, Listing 4).

With probability P_u(mu_o, r) the uniform lobe is used, otherwise the CLTC lobe; the pdf
of the combined strategy is the mixture P_u/(2 pi) + P_c pdf_CLTC (P_c = 1 - P_u), which
makes the estimator unbiased where CLTC misses a lune and bounds the throughput weight.
At r = 0, P_u = 0 and M = I: the sampler is cosine sampling.
"""

from .._jit import kernel
from .ltc import cltc_coeffs, from_frame, ltc_pdf_local, ltc_sample_local, to_frame
from .simple import INV_2PI, U_MAX, uniform_sample


def _binomial_series(a, n):
    """Coefficients c_k of (1 - t)^a = sum_k c_k t^k: c_0 = 1, c_(k+1) = c_k (k - a)/(k + 1)."""
    c = [1.0]
    for k in range(n - 1):
        c.append(c[-1] * (k - a) / (k + 1))
    return tuple(c)


#: (1 - t)^0.1 to t^13: for t <= 1 - 2^-1/8 the first omitted term is < 4e-18.  Stored from
#: the highest power down (Horner's order): the leading coefficient and the others.
_SERIES = _binomial_series(0.1, 14)
_B_TOP, _B_REST = _SERIES[-1], _SERIES[-2::-1]


def _stage(k):
    """(2^-k, 2^k, 2^(-k/10)): one step of the range reduction of ``pow_tenth``."""
    return 2.0**-k, 2.0**k, 2.0 ** (-0.1 * k)


_STAGES = tuple(
    _stage(k) for k in (1000.0, 512.0, 256.0, 128.0, 64.0, 32.0, 16.0, 8.0, 4.0, 2.0, 1.0, 0.5, 0.25, 0.125)
)


@kernel
def _reduce(x, f, stage):
    """If x < 2^-k: x <- x 2^k and f <- f 2^(-k/10), so that f x^0.1 is unchanged."""
    lim, up, fac = stage
    c = x < lim
    return (x * up if c else x), (f * fac if c else f)


@kernel
def pow_tenth(r: float) -> float:
    """r^0.1 for r in [0, 1], to 5e-15 relative, without a libm call (keeps loops vectorisable).

    Range reduction by selects: r = 2^-e x with x in [2^-1/8, 1] (exponent stages 2^-1000
    for subnormal r, then 2^-512, ..., 2^-1, 2^-1/2, 2^-1/4, 2^-1/8), r^0.1 = 2^(-e/10)
    x^0.1, and x^0.1 = (1 - t)^0.1 by its binomial series in t = 1 - x <= 0.083 (Horner).
    r = 0 gives 0.  Both loops run over constant tuples: LLVM unrolls them and the batch loops
    that call this stay vectorised.
    """
    x, f = r, 1.0
    for stage in _STAGES:
        x, f = _reduce(x, f, stage)
    t = 1.0 - x
    p = _B_TOP
    for b in _B_REST:
        p = p * t + b
    return f * p if r > 0.0 else 0.0


#: The coefficients of Listing 4's P_u = r^0.1 (P0 + mu (P1 + (P2 + P3 mu) mu)) (also read by ``export``).
UNIFORM_FIT = (0.162925, -0.372058, 0.538233, -0.290822)


@kernel
def uniform_probability(mu: float, r_tenth: float) -> float:
    """P_u = r^0.1 (0.162925 + mu (-0.372058 + (0.538233 - 0.290822 mu) mu)) (Listing 4),
    given r_tenth = r^0.1 (``pow_tenth(r)``: once per material when r is fixed)."""
    P0, P1, P2, P3 = UNIFORM_FIT
    return r_tenth * (P0 + mu * (P1 + (P2 + P3 * mu) * mu))


@kernel
def eon_sample(
    Xx: float, Xy: float, mu: float, r: float, r_tenth: float, u1: float, u2: float
) -> tuple[float, float, float, float]:
    """Return (x, y, z, pdf) in the local frame: Listing 4 for the LTC frame X of wo
    (r_tenth = r^0.1, ``pow_tenth(r)``).

    The branch test is u1 < P_u (Listing 4 has <=; they differ only at u1 = P_u) so that
    P_u = 0 (r = 0) never selects the uniform lobe.  The rescaled (u1 - P_u)/P_c can round
    to 1 for u1 just below 1 (at u1 = 1 - 2^-53 for most P_u): it is kept at or below
    ``U_MAX``, the largest float64 below 1, so the CLTC lobe gets a u in [0, 1) as cosine
    sampling does (and "eon" at r = 0 is cosine sampling for every u).
    Both lobes are computed and one is selected: branch-free, the batch loop vectorises
    (the uniform branch's division by P_u = 0 then gives a discarded inf).
    """
    a, b, c, d, s = cltc_coeffs(mu, r)
    Pu = uniform_probability(mu, r_tenth)
    Pc = 1.0 - Pu
    uniform = u1 < Pu
    # uniform lobe, in the local frame as in Listing 4; its CLTC density for the mixture
    ux, uy, uz, _ = uniform_sample(u1 / Pu, u2)
    lx, ly = to_frame(Xx, Xy, ux, uy)
    pu = ltc_pdf_local(a, b, c, d, s, lx, ly, uz)
    # CLTC lobe
    lx, ly, cz, pc = ltc_sample_local(a, b, c, d, s, min((u1 - Pu) / Pc, U_MAX), u2)
    cx, cy = from_frame(Xx, Xy, lx, ly)
    p = Pu * INV_2PI + Pc * (pu if uniform else pc)
    return (ux if uniform else cx), (uy if uniform else cy), (uz if uniform else cz), p


@kernel
def eon_pdf(lx: float, ly: float, lz: float, mu: float, r: float, r_tenth: float) -> float:
    """P_u/(2 pi) + P_c pdf_CLTC at the LTC-frame direction (lx, ly, lz), lz > 0
    (r_tenth = r^0.1, ``pow_tenth(r)``)."""
    a, b, c, d, s = cltc_coeffs(mu, r)
    Pu = uniform_probability(mu, r_tenth)
    return Pu * INV_2PI + (1.0 - Pu) * ltc_pdf_local(a, b, c, d, s, lx, ly, lz)
