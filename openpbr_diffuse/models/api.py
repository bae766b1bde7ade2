"""Public lobe-model verbs: ``evaluate``, ``directional_albedo``, ``average_albedo``."""

from collections.abc import Callable, Sequence
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar
from .registry import model_info


def _recheck(bad: int, size: int, checks: Sequence[Callable[[], object]]) -> None:
    """After a kernel with fused value checks: run the full checks to raise their message.

    ``bad`` (nonzero) when some rows failed in the kernel (its output is then discarded); an empty batch ran
    no kernel, so its (scalar) inputs are checked here.
    """
    if bad or not size:
        for check in checks:
            check()
    if bad:  # the kernel and the checks use the same predicates: not reached
        raise ValueError("some rows failed the input checks")


def evaluate(
    model: str,
    wi: ArrayLike,
    wo: ArrayLike,
    roughness: ArrayLike,
    rho: ArrayLike = 1.0,
    *,
    color_mode: str = "reference",
) -> NDArray[Any]:
    """BRDF value f(wi, wo) of a lobe model, without the cosine factor.

    Parameters
    ----------
    model : str
        One of ``MODELS``.
    wi, wo : array_like, shape (..., 3)
        Unit directions towards the light and the viewer, local frame (normal +z), both
        pointing away from the surface.  Either below the horizon (z <= 0) gives f = 0.
    roughness : array_like, shape (...)
        sigma in radians, [0, pi/2], for "qon*", "full_on", "gotanda"; r in [0, 1] for
        "fon", "eon", "eon_approx"; ignored by "lambert".
    rho : array_like, shape (..., C)
        Single-scattering albedo per channel in [0, 1] (1, 3 or N spectral channels).
    color_mode : {"reference", "white_tint"}
        "reference" (default) evaluates with the chromatic rho (EON's rho_ms gives the
        physical colour shift, Eq. 18); "white_tint" evaluates at rho = 1 and multiplies by
        rho (no colour shift; identical for models linear in rho).

    Returns
    -------
    ndarray, shape broadcast(leading axes) + (C,), dtype float32 or float64.

    Notes
    -----
    dtype: float32 only when every float array among wi, wo, roughness, rho is float32
    (Python scalars and lists do not count); then it is computed in float32, within
    16 ulp (float32) of max(|f|, rho/pi) of the float64 result on the same inputs (256
    for "full_on"); see docs/guide/models.md.  Direction arguments: ``wi=``, ``wo=`` by
    keyword in any order; positionally (wi, wo), whereas ``pdf`` takes (wo, wi).

    References
    ----------
    EON paper Eq. 1-4 (QON), 10-11 (FON), 16-19 (EON); Oren & Nayar 1994 (full model);
    Fujii 2013; Gotanda 2012 Eq. 25.

    Examples
    --------
    >>> import numpy as np
    >>> wi = np.array([0.0, 0.0, 1.0]); wo = np.array([0.6, 0.0, 0.8])
    >>> float(evaluate("lambert", wi, wo, 0.0, 1.0)[0] * np.pi)
    1.0
    """
    info = model_info(model)
    tint = ar.white_tint(color_mode)
    dtype = ar.result_dtype(wi, wo, roughness, rho)
    # types and shapes here; the value checks run inside the kernel's loop (one pass over
    # the inputs instead of one per argument), and in full only if it reports a failure
    wi = ar.directions("wi", wi, dtype, check=False)
    wo = ar.directions("wo", wo, dtype, check=False)
    r = ar.model_roughness(info, roughness, dtype, check=False)
    rho = ar.rho_array("rho", rho, dtype, check=False)
    lead = ar.broadcast_leading(wi=wi.shape[:-1], wo=wo.shape[:-1], roughness=r.shape, rho=rho.shape[:-1])
    C = rho.shape[-1]
    from ._kernels import evaluate_rows

    out, bad = evaluate_rows(info.id, tint, 0.0, info.roughness_max, wi, wo, r, rho, lead, C, dtype)
    _recheck(
        bad,
        out.size,
        (
            lambda: ar.directions("wi", wi, dtype),
            lambda: ar.directions("wo", wo, dtype),
            lambda: ar.model_roughness(info, r, dtype),
            lambda: ar.rho_array("rho", rho, dtype),
        ),
    )
    return out.reshape(lead + (C,))


def _albedo(
    model: str, mu: ArrayLike | None, roughness: ArrayLike, rho: ArrayLike, color_mode: str, average: bool
) -> NDArray[Any]:
    info = model_info(model)
    tint = ar.white_tint(color_mode)
    if not info.closed_form_albedo:
        from .tables import table_albedo

        return table_albedo(info.name, mu, roughness, rho, average=average, tint=tint)
    dtype = ar.result_dtype(roughness, rho) if average else ar.result_dtype(mu, roughness, rho)
    mu_what = " (cosine of the view angle)"
    mu = (
        np.zeros((), dtype)
        if average
        else ar.in_range("mu", cast(ArrayLike, mu), dtype, 0.0, 1.0, mu_what, check=False)
    )
    r = ar.model_roughness(info, roughness, dtype, check=False)
    rho = ar.rho_array("rho", rho, dtype, check=False)
    lead = ar.broadcast_leading(mu=mu.shape, roughness=r.shape, rho=rho.shape[:-1])
    C = rho.shape[-1]
    from ._kernels import albedo_rows

    out, bad = albedo_rows(info.id, tint, average, 0.0, info.roughness_max, mu, r, rho, lead, C, dtype)
    _recheck(
        bad,
        out.size,
        (
            lambda: ar.in_range("mu", mu, dtype, 0.0, 1.0, mu_what),
            lambda: ar.model_roughness(info, r, dtype),
            lambda: ar.rho_array("rho", rho, dtype),
        ),
    )
    return out.reshape(lead + (C,))


def directional_albedo(
    model: str, mu: ArrayLike, roughness: ArrayLike, rho: ArrayLike = 1.0, *, color_mode: str = "reference"
) -> NDArray[Any]:
    """Directional albedo E(mu) = integral of f(wi, wo) mu_i dwi over the upper hemisphere.

    Closed forms: Lambert E = rho; QON family Eq. 8 (E = A + B G(theta)/pi); FON Eq. 12-13;
    EON Eq. 20; Gotanda and Fujii QON, whose lobes have FON's shape (A + B s/t)/pi, take
    E = A + B G_F/pi.  "eon_approx" returns the exact albedo of its lobe (Eq. 20 with the
    mean of the Eq. 14 fit in place of <E_F>; < 5e-4 from Eq. 20).  "full_on" has no closed
    form: its albedo is interpolated from the shipped reference tables.

    Parameters
    ----------
    mu : array_like, shape (...)
        Cosine of the outgoing direction, in [0, 1] (mu = 0 gives the limit).
    roughness, rho, color_mode : as in ``evaluate``.

    Returns
    -------
    ndarray, shape broadcast(mu, roughness, rho leading axes) + (C,).  float32 when
    every float array among mu, roughness, rho is float32, computed in float32 within
    8 ulp of the float64 result (closed forms; "full_on" interpolates its table).

    Examples
    --------
    >>> round(float(directional_albedo("fon", 1.0, 1.0)[0]), 6)   # EON paper: E_F(1, 1)
    0.776522
    """
    return _albedo(model, mu, roughness, rho, color_mode, average=False)


def average_albedo(
    model: str, roughness: ArrayLike, rho: ArrayLike = 1.0, *, color_mode: str = "reference"
) -> NDArray[Any]:
    """Cosine-weighted average albedo <E> = 2 int_0^1 E(mu) mu dmu (QON Eq. 9, FON Eq. 15).

    Examples
    --------
    >>> round(float(average_albedo("fon", 1.0)[0]), 6)   # EON paper: <E_F>(1)
    0.832811
    """
    return _albedo(model, None, roughness, rho, color_mode, average=True)
