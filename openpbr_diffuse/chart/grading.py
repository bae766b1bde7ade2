"""Grading a rendered chart image: exposure, linearity, then the BRDF on the tiles.

1. Every tile's interior mean and standard error (:mod:`.image`).
2. Exposure: the ramp and white tiles (roughness 0: rho/pi in every model) give the
   least-squares factor c between the measured and the stated values (``absolute``: c = 1,
   graded against the stated irradiance).
3. Linearity: a ramp value off the line c e by more than its tolerance is non-linear
   output -- unless a power law fitted to the ramp has a gamma within its uncertainty of 1
   (it moves the ramp end to end by at most :data:`LINEAR_SPAN` or :data:`LINEAR_SCATTER`
   times the ramp's scatter about it: a rasteriser's error, not a curve).  The sRGB curve and a power law a e^gamma are fitted; the better one is named
   ("sRGB-encoded", "gamma ~ 2.2"), the image is linearised with it and the BRDF graded
   after that -- the verdict stays "does not conform" (the render settings are wrong).
4. The test tiles become rows (wi, wo, roughness, rho, out = value / (mu_i E c); in the
   furnace albedo rows, out = value / (L c)) graded by
   :func:`openpbr_diffuse.conformance.grade.grade`, with its diagnosis by the catalogue of
   known deviations.

The tolerance (one for every row, as ``grade`` takes it):

    relative  IMAGE_REL_TOL + the chart's interreflection bound + K sigma_c / c
              + the renderer's floor + max over the tiles of (K stderr + q) / value
    absolute  max over the dark tiles (value < DARK) of (K stderr + q) / (mu_i E c)

The tiles much noisier than the median tile (:data:`NOISY_FACTOR`) are graded apart with
a tolerance of their own (a grazing tile where a few samples miss), so that they do not
widen the tolerance of the others.
The renderer's floor is its own error at roughness 0, where every model is rho/pi: the
largest scatter of a ramp / white tile about the exposure line beyond that tile's noise
band (0 for a path tracer whose ramp is within its noise; EEVEE: 3.6e-3), at most
:data:`FLOOR_CAP` (a ramp scattering more is a broken image, not a renderer's small error).
With K = :data:`K_SIGMA` standard errors of a tile's mean (a path tracer's noise), q half a
code value of an integer file (rasteriser output), sigma_c the standard error of the
exposure factor.  IMAGE_REL_TOL covers half-float storage (4.9e-4 relative) and the
renderer's float32 geometry; the smallest deviation in the catalogue (an extra rho on
f_ms) moves coloured tiles by several percent.

Example
-------
>>> from openpbr_diffuse.chart.layout import build_scene
>>> from openpbr_diffuse.chart.expected import expected_image
>>> s = build_scene(35.0, resolution=256)
>>> g = grade_image(2.0 * expected_image(s), s)
>>> g.passed, round(g.exposure, 4)
(True, 2.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..result import COMMON_KEYS, Result
from .image import ChartImage, quantisation_step, tile_stats

#: Standard errors of a tile's mean allowed (a 4-sigma band: 6e-5 two-sided per tile).
K_SIGMA = 4.0
#: Relative tolerance of a rendered value: half-float storage and float32 geometry.
IMAGE_REL_TOL = 2e-3
#: A tile value (BRDF units) below which its noise counts in the absolute tolerance.
DARK = 1e-2
#: A tile whose relative noise is above this many times the median tile's is graded apart.
NOISY_FACTOR = 4.0
#: Largest renderer floor accepted (relative): a ramp that scatters more than this about the
#: exposure line is not a renderer's own small error but a broken image (tiles missing,
#: clamped, shadowed); the floor is capped here and the image is graded with the cap.
FLOOR_CAP = 0.02
#: A power law fitted to the ramp is linear output when it moves the ramp, end to end, by at
#: most this (|gamma - 1| ln(e_max / e_min)) or by no more than the ramp's scatter about it:
#: a rasteriser's own error at roughness 0 is of this size (EEVEE: 0.36 % on the darkest ramp
#: tile, a fitted gamma of 1.001), a transfer curve by far more (sRGB or gamma 2.2: > 100 %).
LINEAR_SPAN = 0.01
#: ... or by at most this many times the ramp's largest relative scatter about the fitted power
#: law (tile-to-tile errors of a rasteriser tilt a fitted gamma by about that much).
LINEAR_SCATTER = 4.0


@dataclass
class ImageGrade(Result):
    """The result of :func:`grade_image`: a :class:`~openpbr_diffuse.result.Result` (the
    BRDF's largest error in tolerances, the finding, the worst tiles' rows) with what the
    image told about the renderer's output (exposure, linearity, light); ``grade`` is the
    :class:`~openpbr_diffuse.conformance.grade.Grade` of the BRDF rows (``to_dict()`` for JSON)."""

    kind: str = "quantity"
    grade: Any = None
    exposure: float = math.nan
    exposure_stderr: float = math.nan
    absolute: bool = False
    non_linear: str | None = None
    linearised: bool = False
    n_tiles: int = 0
    light: str = ""
    ramp_residual: float = math.nan
    brdf_passed: bool = True

    def to_dict(self) -> dict[str, Any]:
        from ..conformance.grade import json_safe

        own = Result.to_dict(self)
        d = self.grade.to_dict()
        d.update({key: own[key] for key in COMMON_KEYS})
        d.update(
            json_safe(
                {
                    "passed": self.passed,
                    "brdf_passed": self.brdf_passed,
                    "exposure": self.exposure,
                    "exposure_stderr": self.exposure_stderr,
                    "absolute": self.absolute,
                    "non_linear": self.non_linear,
                    "linearised": self.linearised,
                    "image_tolerance": self.tolerance,
                    "n_tiles": self.n_tiles,
                    "light": self.light,
                    "ramp_max_rel_residual": self.ramp_residual,
                }
            )
        )
        return d


def _calibration_expected(tiles, light):
    """Stated value of every ramp / white tile: rho mu_i E / pi, or rho L (furnace)."""
    out = []
    for t in tiles:
        rho = np.asarray(t["rho"], float)
        if light["kind"] == "furnace":
            out.append(rho * light["radiance"])
        else:
            e = t["irradiance"] if light["kind"] == "point" else light["irradiance"]
            out.append(rho * max(t["wi"][2], 0.0) * e / math.pi)
    return np.array(out)


def _fit(m, e, w):
    den = float(np.sum(w * e * e))
    c = float(np.sum(w * m * e) / den) if den > 0 else math.nan
    return c


def _linearity(m, e, tol):
    """(None, identity) when the ramp is linear, else (name, linearise(values) -> values)."""
    from ..conformance.deviations import srgb_decode, srgb_encode

    c = _fit(m, e, 1.0 / np.maximum(tol, 1e-12) ** 2)
    if np.all(np.abs(m - c * e) <= tol + 1e-12):
        return None, None
    ok = (m > 0) & (e > 0)
    if ok.sum() >= 3 and np.ptp(np.log(e[ok])) > 0:
        # a gamma within its uncertainty of 1 is linear output with scatter (not a curve)
        span = float(np.ptp(np.log(e[ok])))
        g1, la = np.polyfit(np.log(e[ok]), np.log(m[ok]), 1)
        scatter = float(np.max(np.abs(math.exp(la) * e[ok] ** g1 / m[ok] - 1.0)))
        if abs(float(g1) - 1.0) * span <= max(LINEAR_SPAN, LINEAR_SCATTER * scatter):
            return None, None
    cands = []
    dec = srgb_decode(m)
    cd = _fit(dec, e, 1.0)
    if cd > 0:
        res = float(np.max(np.abs(dec[ok] / (cd * e[ok]) - 1.0))) if ok.any() else math.inf
        cands.append((res, "sRGB-encoded (the sRGB transfer applied to linear values)", lambda x: srgb_decode(x)))
    if ok.sum() >= 2:
        gamma, loga = np.polyfit(np.log(e[ok]), np.log(m[ok]), 1)
        a = math.exp(loga)
        res = float(np.max(np.abs(a * e[ok] ** gamma / m[ok] - 1.0)))
        g = float(gamma)
        cands.append(
            (
                res,
                f"gamma ~ {1.0 / g:.2f} (values ~ a (linear)^{g:.3f})",
                lambda x, a=a, g=g: np.sign(x) * (np.abs(x) / a) ** (1.0 / g),
            )
        )
    top = float(m.max())
    near_top = m >= top * (1 - 1e-3)
    if near_top.sum() >= 2 and e[near_top].max() > 1.05 * e[near_top].min():
        cands.append((0.0, f"clamped at {top:.4g}", None))
    if not cands:
        return "non-linear output (no curve fits the ramp)", None
    res, name, fn = min(cands, key=lambda x: x[0])
    _ = srgb_encode  # the grader's sRGB pair is the catalogue's (conformance.deviations)
    return name, fn


@dataclass
class _Exposure:
    """What the ramp and white tiles give: the exposure, the output curve and the renderer's floor."""

    means: np.ndarray  # every tile's mean, linearised when the ramp showed a curve
    non_linear: str | None
    linearised: bool
    fitted: float  # the exposure factor fitted to the ramp
    stderr: float  # its standard error
    factor: float  # the factor the tiles are graded with (1 when absolute)
    ramp_residual: float
    floor: float  # the renderer's floor, capped at FLOOR_CAP
    floor_measured: float


def _checked_inputs(
    image: np.ndarray | ChartImage, chart: dict[str, Any], model: str
) -> tuple[dict[str, Any], ChartImage, Any]:
    """The validated chart, ``image`` as a ChartImage (an array is linear float data) and its
    tiles' statistics; ValueError for an unknown model, an image of the wrong size or NaN tiles."""
    from ..conformance.vectors import ALL_VECTOR_MODELS
    from .schema import validate

    if model not in ALL_VECTOR_MODELS:
        raise ValueError(f"model: expected one of {', '.join(ALL_VECTOR_MODELS)}, got {model!r}")
    chart = validate(chart)
    if not isinstance(image, ChartImage):
        image = ChartImage(np.asarray(image, np.float32), "linear", 0)
    px = image.pixels
    if px.ndim != 3 or px.shape[2] != 3:
        raise ValueError(f"image: expected (height, width, 3) RGB, got shape {px.shape}")
    if px.shape[:2] != (chart["height"], chart["width"]):
        raise ValueError(f"image: {px.shape[1]}x{px.shape[0]} pixels, the chart is {chart['width']}x{chart['height']}")
    stats = tile_stats(px, chart["tiles"])
    if not np.isfinite(stats.mean).all():
        raise ValueError("image: NaN or Inf pixels inside the tiles")
    return chart, image, stats


def _base_relative(
    chart: dict[str, Any], rows: list[dict[str, Any]], x: _Exposure, k_sigma: float, absolute: bool
) -> float:
    """The relative tolerance every test tile shares: IMAGE_REL_TOL, the interreflection bound,
    the point light's variation over a tile, the renderer's floor and (unless ``absolute``)
    K standard errors of the exposure."""
    variation = max((float(t.get("variation", 0.0)) for t in rows), default=0.0)
    rel0 = IMAGE_REL_TOL + float(chart.get("interreflection_bound", 0.0)) + variation + x.floor
    if not absolute:
        rel0 += k_sigma * x.stderr / x.factor
    return rel0


def _renderer_floor(m: np.ndarray, e: np.ndarray, band: np.ndarray, c_fit: float) -> tuple[float, float]:
    """The renderer's own error at roughness 0 (where every model is rho/pi): the ramp's scatter
    about the exposure line beyond each tile's noise band, as measured and capped at FLOOR_CAP."""
    with np.errstate(divide="ignore", invalid="ignore"):
        beyond = np.abs(m / (c_fit * e) - 1.0) - band / np.abs(c_fit * e)
    floor = float(np.max(np.where(np.isfinite(beyond) & (e > 0), beyond, 0.0), initial=0.0))
    floor_measured = max(floor, 0.0)
    return floor_measured, min(floor_measured, FLOOR_CAP)


def _exposure(
    stats: Any, q: np.ndarray, cal: np.ndarray, chart: dict[str, Any], k_sigma: float, absolute: bool
) -> _Exposure:
    """Linearity and exposure from the calibration tiles ``cal`` (ramp and white): a curve
    found on the ramp linearises every tile; the exposure is the weighted least-squares factor."""
    e = _calibration_expected([t for t, c in zip(chart["tiles"], cal, strict=True) if c], chart["light"])
    m = stats.mean[cal]
    band = k_sigma * stats.stderr[cal] + q[cal] + IMAGE_REL_TOL * np.abs(m)
    non_linear, linearise = _linearity(m.ravel(), e.ravel(), band.ravel())
    means = stats.mean
    linearised = False
    if non_linear is not None and linearise is not None:
        means = linearise(means)
        m = means[cal]
        linearised = True
    w = 1.0 / np.maximum(k_sigma * stats.stderr[cal] + q[cal] + 1e-4 * np.abs(e), 1e-12) ** 2
    c_fit = _fit(m, e, w)
    if not (math.isfinite(c_fit) and c_fit > 0):
        raise ValueError("image: the ramp tiles are black or negative: no exposure to calibrate on")
    se_c = float(math.sqrt(np.sum((e * stats.stderr[cal]) ** 2)) / np.sum(e * e))
    c = 1.0 if absolute else c_fit
    ramp_res = float(np.max(np.abs(m / (c * e) - 1.0)))
    floor_measured, floor = _renderer_floor(m, e, band, c_fit)
    return _Exposure(means, non_linear, linearised, c_fit, se_c, c, ramp_res, floor, floor_measured)


def _test_vectors(rows: list[dict[str, Any]], light: dict[str, Any], model: str) -> tuple[Any, np.ndarray]:
    """The test tiles ``rows`` as graded vectors (BRDF rows; albedo rows in the furnace) and
    each row's light: mu_i E (distant, point) or L (furnace)."""
    from ..conformance.vectors import VectorSet

    n = len(rows)
    wo = np.array([t["wo"] for t in rows], float)
    if light["kind"] == "furnace":
        kind = np.full(n, "albedo")
        wi = np.full((n, 3), np.nan)
        mu = wo[:, 2].copy()
        scale = np.full(n, float(light["radiance"]))
        wo_rows = np.full((n, 3), np.nan)
    else:
        kind = np.full(n, "brdf")
        wi = np.array([t["wi"] for t in rows], float)
        mu = np.full(n, np.nan)
        irr = np.array([t["irradiance"] if light["kind"] == "point" else light["irradiance"] for t in rows], float)
        scale = np.maximum(wi[:, 2], 1e-12) * irr
        wo_rows = wo
    vectors = VectorSet(
        np.array([t["id"] for t in rows]),
        kind,
        np.full(n, model),
        wi,
        wo_rows,
        mu,
        np.array([t["roughness"] for t in rows], float),
        np.array([t["rho"] for t in rows], float),
        "chart",
    )
    return vectors, scale


def _grade_groups(
    vectors: Any, out: np.ndarray, noise: np.ndarray, rel0: float
) -> dict[str, tuple[Any, float, float, int]]:
    """Grade the rows: ``{"main": (grade, rel, abs, n)}``, and ``"noisy"`` for the tiles much
    noisier than the typical one, graded apart at their own tolerance."""
    from ..conformance.grade import grade

    # a tile's noise is relative to its value (a path tracer's, a quantisation step): the
    # bright channels give a relative band, the dark ones (BRDF value < DARK) an absolute one
    bright = np.abs(out) >= DARK
    rel_noise = np.where(bright, noise / np.where(bright, np.abs(out), 1.0), 0.0).max(axis=1)
    abs_noise = np.where(bright, 0.0, noise).max(axis=1)
    # the tiles much noisier than the typical one are graded apart, at their own tolerance,
    # so that a few noisy tiles do not widen everyone's
    noisy = rel_noise > max(NOISY_FACTOR * float(np.median(rel_noise)), 1e-4)
    groups = [("main", ~noisy)] + ([("noisy", noisy)] if noisy.any() else [])
    grades = {}
    for name, sel in groups:
        rel = rel0 + float(rel_noise[sel].max())
        ab = max(float(abs_noise[sel].max()), 1e-6)
        grades[name] = (grade(vectors.subset(sel), out[sel], tolerance=(rel, ab)), rel, ab, int(sel.sum()))
    return grades


def _tolerance(grades: dict[str, tuple[Any, float, float, int]], k_sigma: float, x: _Exposure) -> dict[str, Any]:
    """The image tolerance as ImageGrade reports it: the main tiles' bands and their rule, and
    the noisy tiles' own."""
    _, rel, ab, _ = grades["main"]
    floor, floor_measured = x.floor, x.floor_measured
    tol: dict[str, Any] = {
        "relative": rel,
        "absolute": ab,
        "k_sigma": k_sigma,
        "renderer_floor": floor,
        "renderer_floor_measured": floor_measured,
        "rule": (
            f"|out - ref| <= {ab:.3g} + {rel:.3g} |ref| per tile: {IMAGE_REL_TOL:g} (half float, float32 geometry) "
            f"+ the interreflection bound + the renderer's own error on the ramp ({floor:.2g}: its scatter "
            f"about the exposure line beyond the tiles' noise"
            + (
                f", measured {floor_measured:.2g}, capped at {FLOOR_CAP:g}: the calibration tiles themselves are wrong"
                if floor_measured > FLOOR_CAP
                else ""
            )
            + f") + {k_sigma:g} standard errors of the exposure + "
            f"{k_sigma:g} standard "
            "errors of the noisiest tile's mean and half a code value, relative to its value (absolute for "
            f"BRDF values < {DARK:g})"
        ),
    }
    if "noisy" in grades:
        gn, rn, an, nn = grades["noisy"]
        tol["noisy_tiles"] = {
            "n": nn,
            "relative": rn,
            "absolute": an,
            "n_failed": gn.n_failed_rows,
            "passed": gn.passed,
            "why": f"noise above {NOISY_FACTOR:g}x the median tile's: graded apart at their own tolerance",
        }
    return tol


def grade_image(
    image: np.ndarray | ChartImage,
    chart: dict[str, Any],
    *,
    model: str = "eon",
    absolute: bool = False,
    k_sigma: float = K_SIGMA,
) -> ImageGrade:
    """Grade a rendered image of a chart scene.

    Parameters
    ----------
    image : ndarray (h, w, 3) or ChartImage
        Linear RGB (an array is taken as linear float data).
    chart : dict
        The scene's chart.json document (:func:`.schema.read_chart`).
    model : str
        The model the renderer is graded against (a vector model; default EON).
    absolute : bool
        Grade against the stated irradiance (exposure fixed at 1) instead of the ramp's factor.
    k_sigma : float
        Standard errors of a tile's mean allowed.

    Example
    -------
    >>> from openpbr_diffuse.chart.layout import build_scene
    >>> from openpbr_diffuse.chart.expected import expected_image
    >>> s = build_scene(110.0, resolution=256)
    >>> g = grade_image(expected_image(s, "lambert"), s)
    >>> g.passed, g.grade.diagnosis
    (False, 'no_energy_compensation_lambert')
    """
    chart, image, stats = _checked_inputs(image, chart, model)
    tiles = chart["tiles"]
    q = quantisation_step(image, stats.mean)
    cal = np.array([t["role"] in ("ramp", "white") for t in tiles])
    test = ~cal
    x = _exposure(stats, q, cal, chart, k_sigma, absolute)
    rows = [t for t, s in zip(tiles, test, strict=True) if s]
    vectors, scale = _test_vectors(rows, chart["light"], model)
    out = x.means[test] / (x.factor * scale[:, None])
    noise = (k_sigma * stats.stderr[test] + q[test]) / (x.factor * scale[:, None])
    grades = _grade_groups(vectors, out, noise, _base_relative(chart, rows, x, k_sigma, absolute))
    g, rel, _, _ = grades["main"]
    brdf_ok = g.passed and ("noisy" not in grades or grades["noisy"][0].passed)
    passed = bool(brdf_ok and x.non_linear is None and (not absolute or x.ramp_residual <= rel + 1e-3))
    return ImageGrade(
        id="image.brdf",
        quantity="chart image",
        outcome="pass" if passed else "fail",
        measured=g.measured,
        threshold=g.threshold,
        diagnosis=g.diagnosis,
        worst=list(g.worst),
        detail=g.diagnosis_detail,
        grade=g,
        exposure=x.fitted,
        exposure_stderr=x.stderr,
        absolute=absolute,
        non_linear=x.non_linear,
        linearised=x.linearised,
        tolerance=_tolerance(grades, k_sigma, x),
        n_tiles=len(tiles),
        light=chart["light"]["kind"],
        ramp_residual=x.ramp_residual,
        brdf_passed=bool(brdf_ok),
    )


__all__ = ["ImageGrade", "grade_image", "K_SIGMA", "IMAGE_REL_TOL"]
