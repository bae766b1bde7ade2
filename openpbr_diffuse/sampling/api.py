"""Public sampling verbs: ``sample``, ``pdf`` and ``sample_rng``."""

import numbers
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, DTypeLike, NDArray

from .. import _arrays as ar
from .registry import STRATEGIES, strategy_info  # noqa: F401  (STRATEGIES re-exported)


def _roughness(roughness: ArrayLike, dtype: DTypeLike) -> NDArray[Any]:
    return ar.in_range("roughness", roughness, dtype, 0.0, 1.0, " (EON's r, a weight)")


def sample(strategy: str, wo: ArrayLike, roughness: ArrayLike, u: ArrayLike) -> tuple[NDArray[Any], NDArray[Any]]:
    """Draw incident directions wi given wo, with the caller's uniform numbers u.

    Parameters
    ----------
    strategy : str
        One of ``STRATEGIES``: "cosine" (Eq. 21), "uniform", "ltc" (the general LTC fit of
        Listing 2; its lobe extends below the horizon and such samples are returned as
        they are, with their LTC density: the BRDF is zero there, so their weight is 0),
        "ltc_nonneg" (d = 0), "cltc" (clipped LTC, Eq. 27-28, Listing 3) or "eon"
        (CLTC + uniform, one-sample MIS, Listing 4: the EON sampler).
    wo : array_like, shape (..., 3)
        Unit direction towards the viewer, local frame (normal +z).  Below the horizon
        (wo.z <= 0) there is nothing to sample (f = 0): a finite direction is returned
        (that of wo.z = 0) with pdf = 0, the usual "discard this sample" marker.
    roughness : array_like, shape (...)
        EON's r in [0, 1]; ignored by "cosine" and "uniform".
    u : array_like, shape (..., 2)
        Uniform random numbers in [0, 1).  u[..., 0] picks the MIS lobe (rescaled) and
        the radius, u[..., 1] the azimuth.

    Returns
    -------
    wi : ndarray, shape broadcast(leading axes) + (3,)
        Unit sampled directions; z > 0 for every u in [0, 1)^2 except with "ltc" (z is
        floored at the dtype's smallest normal number, which only rounding reaches).
    pdf : ndarray, shape broadcast(leading axes)
        Solid-angle density of wi: ``pdf(strategy, wo, wi, roughness)`` evaluated on the
        returned (rounded) wi, so the two agree to the last bits for every u; > 0 whenever
        wo is above the horizon (no discards at u = 0 or at the largest value below 1).

    Notes
    -----
    "eon" at r = 0 returns the directions of "cosine" (to rounding) for every u: M = I
    and P_u = 0.  The uniform lobe (and the uniform branch of "eon") maps u1 = 0 to
    z = 0, which the floor lifts to the smallest normal number: a direction on the
    horizon, with f mu_i / pdf = 0, and a pdf that ``pdf`` agrees with.

    References
    ----------
    EON paper (Portsmouth, Kutz, Hill, JCGT 2025) Section 3.1, Eq. 21-28, Listings 2-4;
    Heitz et al. 2016 (LTC); Heitz 2018 (sampling the half disk + half ellipse).

    Examples
    --------
    >>> import numpy as np
    >>> wi, p = sample("cosine", np.array([0.0, 0.0, 1.0]), 0.5, np.array([0.36, 0.0]))
    >>> wi.round(12).tolist(), round(float(p * np.pi), 12)   # R = 0.6, x = -R cos(0), pdf = z/pi
    ([-0.6, 0.0, 0.8], 0.8)
    >>> wi, p = sample("eon", np.array([0.6, 0.0, 0.8]), 1.0, np.array([[0.1, 0.3], [0.7, 0.9]]))
    >>> np.allclose(p, pdf("eon", np.array([0.6, 0.0, 0.8]), wi, 1.0))
    True
    """
    info = strategy_info(strategy)
    dtype = ar.result_dtype(wo, roughness, u)
    wo = ar.directions("wo", wo, dtype)
    r = _roughness(roughness, dtype)
    u = ar.unit_samples("u", u, dtype)
    lead = ar.broadcast_leading(wo=wo.shape[:-1], roughness=r.shape, u=u.shape[:-1])
    from ._kernels import sample_rows

    return sample_rows(info.id, wo, r, u, lead, dtype)


def pdf(strategy: str, wo: ArrayLike, wi: ArrayLike, roughness: ArrayLike) -> NDArray[Any]:
    """Solid-angle pdf of sampling wi given wo with ``strategy``.

    Positionally wo comes first, (strategy, wo, wi, roughness), the reverse of
    ``evaluate(model, wi, wo, ...)``; ``wi=`` and ``wo=`` as keywords bind by name in any
    order and are the safe form: the pdf is not symmetric, and swapped positional
    arguments give another value without an error.

    Parameters
    ----------
    strategy : str
        One of ``STRATEGIES`` (see ``sample``).
    wo, wi : array_like, shape (..., 3)
        Unit directions (viewer, light), local frame.  pdf = 0 when wo.z <= 0, and when
        wi.z <= 0 except for "ltc", whose lobe extends below the horizon: there it returns
        the LTC density (the "ltc" pdf integrates to 1 over the sphere, to less than 1
        over the upper hemisphere).
    roughness : array_like, shape (...)
        EON's r in [0, 1]; ignored by "cosine" and "uniform".

    Returns
    -------
    ndarray, shape broadcast(leading axes)

    Notes
    -----
    "cosine": mu_i/pi.  "uniform": 1/(2 pi).  LTC family: (det M/|h|^2)^2 max(h.z, 0)/(pi s)
    with h = adj(M) w in the LTC frame (Eq. 23-26; s = 1, or (1 + 1/sqrt(1 + d^2))/2 for
    CLTC, Eq. 28).  "eon": P_u/(2 pi) + (1 - P_u) pdf_CLTC (Listing 4).

    Examples
    --------
    >>> import numpy as np
    >>> z = np.array([0.0, 0.0, 1.0])
    >>> round(float(pdf("uniform", z, z, 1.0) * 2 * np.pi), 12)
    1.0
    >>> wi = np.array([0.6, 0.0, 0.8])
    >>> round(float(pdf("cosine", wi=wi, wo=z, roughness=0.0) * np.pi), 12)   # wi.z / pi
    0.8
    >>> round(float(pdf("cosine", z, wi, 0.0) * np.pi), 12)   # the same call, positional
    0.8
    """
    info = strategy_info(strategy)
    dtype = ar.result_dtype(wo, wi, roughness)
    wo = ar.directions("wo", wo, dtype)
    wi = ar.directions("wi", wi, dtype)
    r = _roughness(roughness, dtype)
    lead = ar.broadcast_leading(wo=wo.shape[:-1], wi=wi.shape[:-1], roughness=r.shape)
    from ._kernels import pdf_rows

    return pdf_rows(info.id, wo, wi, r, lead, dtype)


def sample_rng(
    strategy: str,
    wo: ArrayLike,
    roughness: ArrayLike,
    rng: np.random.Generator | np.random.SeedSequence | np.random.BitGenerator | int | None = None,
    shape: int | tuple[int, ...] | None = None,
) -> tuple[NDArray[Any], NDArray[Any]]:
    """``sample`` with u drawn from a numpy Generator (reproducible with a seed).

    Parameters
    ----------
    strategy, wo, roughness : as in ``sample``.
    rng : numpy.random.Generator, int, numpy.random.SeedSequence or None
        Passed to ``numpy.random.default_rng`` (a Generator is used as is).
    shape : int or tuple of int, optional
        Leading shape of the samples; default broadcast(wo leading axes, roughness).
        Give e.g. ``(n,)`` to draw n samples for one wo.

    Returns
    -------
    wi, pdf : as in ``sample``.  u is drawn in the result dtype (float32 for float32 input).

    Examples
    --------
    >>> import numpy as np
    >>> wi, p = sample_rng("eon", np.array([0.6, 0.0, 0.8]), 1.0, rng=7, shape=(4,))
    >>> wi.shape, p.shape, bool((p > 0).all())
    ((4, 3), (4,), True)
    """
    if not (
        rng is None
        or isinstance(rng, (np.random.Generator, np.random.SeedSequence, np.random.BitGenerator))
        or (isinstance(rng, numbers.Integral) and not isinstance(rng, bool))
    ):
        raise TypeError(
            "rng must be a numpy.random.Generator, a SeedSequence, a BitGenerator, "
            f"a non-negative int seed or None; got {type(rng).__name__}"
        )
    if isinstance(rng, numbers.Integral) and rng < 0:
        raise ValueError(f"rng: an int seed must be non-negative, got {rng}")
    gen = np.random.default_rng(rng)
    dtype = ar.result_dtype(wo, roughness)
    if shape is not None:
        dims = (shape,) if isinstance(shape, numbers.Integral) else shape
        try:
            dims = tuple(dims)  # type: ignore[arg-type]  # an int shape was wrapped (numbers.Integral)
        except TypeError:
            raise TypeError(f"shape must be a tuple of non-negative ints, got {type(shape).__name__}") from None
        if not all(isinstance(d, numbers.Integral) and not isinstance(d, bool) and d >= 0 for d in dims):
            raise ValueError(f"shape must be a tuple of non-negative ints, got {shape!r}")
        shape = tuple(int(d) for d in dims)
    if shape is None:
        w = ar.as_float("wo", wo, dtype)
        r = ar.as_float("roughness", roughness, dtype)
        if w.ndim == 0 or w.shape[-1] != 3:
            raise ValueError(f"wo must have shape (..., 3) (unit direction vectors), got shape {w.shape}")
        shape = ar.broadcast_leading(wo=w.shape[:-1], roughness=r.shape)
    u = gen.random(tuple(shape) + (2,), dtype=dtype)
    return sample(strategy, wo, roughness, u)
