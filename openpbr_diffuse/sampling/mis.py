"""The EON sampler: CLTC plus uniform hemisphere, one-sample MIS (Section 3.1, Listing 4).

With probability P_u(mu_o, r) the uniform lobe is used, otherwise the CLTC lobe; the pdf
of the combined strategy is the mixture P_u/(2 pi) + P_c pdf_CLTC (P_c = 1 - P_u), which
makes the estimator unbiased where CLTC misses a lune and bounds the throughput weight.
At r = 0, P_u = 0 and M = I: the sampler is cosine sampling.
"""
import math

from ..models._jit import kernel
from .ltc import clip_fraction, from_frame, ltc_coeffs, ltc_pdf_local, ltc_sample_local, to_frame
from .simple import INV_2PI, uniform_sample


@kernel
def uniform_probability(mu, r):
    """P_u = r^0.1 (0.162925 + mu (-0.372058 + (0.538233 - 0.290822 mu) mu)) (Listing 4)."""
    if r <= 0.0:
        return 0.0
    rp = math.exp(0.1 * math.log(r))  # r^0.1; exp/log is cheaper than pow here
    return rp * (0.162925 + mu * (-0.372058 + (0.538233 - 0.290822 * mu) * mu))


@kernel
def eon_sample(Xx, Xy, mu, r, u1, u2):
    """Return (x, y, z, pdf) in the local frame: Listing 4 for the LTC frame X of wo.

    The branch test is u1 < P_u (Listing 4 has <=; they differ only at u1 = P_u) so that
    P_u = 0 (r = 0) never selects the uniform lobe, and both rescaled u1 stay in [0, 1).
    """
    a, b, c, d = ltc_coeffs(mu, r)
    s = clip_fraction(d)
    Pu = uniform_probability(mu, r)
    Pc = 1.0 - Pu
    if u1 < Pu:
        wx, wy, wz, _ = uniform_sample(u1 / Pu, u2)
        lx, ly = to_frame(Xx, Xy, wx, wy)
        pc = ltc_pdf_local(a, b, c, d, s, lx, ly, wz)
    else:
        lx, ly, wz, pc = ltc_sample_local(a, b, c, d, s, (u1 - Pu) / Pc, u2)
        wx, wy = from_frame(Xx, Xy, lx, ly)
    return wx, wy, wz, Pu * INV_2PI + Pc * pc


@kernel
def eon_pdf(lx, ly, lz, mu, r):
    """P_u/(2 pi) + P_c pdf_CLTC at the LTC-frame direction (lx, ly, lz), lz > 0."""
    a, b, c, d = ltc_coeffs(mu, r)
    Pu = uniform_probability(mu, r)
    return Pu * INV_2PI + (1.0 - Pu) * ltc_pdf_local(a, b, c, d, clip_fraction(d), lx, ly, lz)
