"""Grade a :class:`.Subject` (an implementation's own code) per quantity.

BRDF values and directional albedos are graded with exactly
``openpbr_diffuse.conformance.grade.grade`` on ``default_vectors()`` (the rows of the model the
implementation claims, one kind at a time), so the verdict and diagnosis are those ``check FILE``
gives for the same numbers.  Samplers are graded by comparing the pdf they report with every
reference strategy's pdf and by a chi-square test of their samples against their own pdf;
surface implementations by the diffuse lobe's weight x albedo and selection probability against
``OpenPBRSurface``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..result import Result, sub_check
from ._arrays import direction

if TYPE_CHECKING:
    from ..conformance.grade import Grade
    from ..conformance.vectors import VectorSet
    from .subject import Subject

#: sampler: pdf normalisation over a (mu_o, roughness) grid, grazing mu_o included (mu_o < 0.2)
SAMPLER_NORM_MU = (0.02, 0.05, 0.1, 0.15, 0.3, 0.5, 0.8, 1.0)
SAMPLER_NORM_R = (0.0, 0.25, 0.5, 1.0)
#: (cos theta, phi) bins of the quadrature and of the chi-square histogram; Gauss-Legendre nodes per bin
SAMPLER_BINS = (16, 32)
SAMPLER_NQ = 4
#: |int pdf dw - 1|: the rule integrates the reference strategies' pdfs to < 1e-5 (measured over this
#: grid), float32 pdf values add < 1e-6; 5e-3 flags a pdf 0.5 % off and stays 20x below a 10 % error
SAMPLER_MASS_TOL = 5e-3
#: sampler: the (mu_o, r) cases whose samples are drawn (a subset of the normalisation grid),
#: phi_o off the x axis (an anisotropic pdf's frame is exercised)
SAMPLER_CASES = tuple((mu, r) for mu in (0.05, 0.3, 0.8) for r in (0.5, 1.0))
SAMPLER_PHI = 0.7
#: samples per case: ONE count for ``check`` and ``report`` (the report reads it from here), so a
#: sampler gets the same chi-square in both
SAMPLER_SAMPLES = 100_000
SAMPLER_ALPHA = 0.01
#: agreement of a pdf with a reference strategy's: relative to max(reference, SAMPLER_PDF_FLOOR)
#: (float32 + llvmpipe arithmetic; the strategies differ by > 10 % somewhere)
SAMPLER_PDF_TOL = 2e-3
SAMPLER_PDF_FLOOR = 1e-2
#: a sampled wi is a unit vector to this absolute tolerance on its length
SAMPLER_UNIT_TOL = 1e-3
#: z in [-SAMPLER_HORIZON_TOL, 0): a direction on the horizon rounded below it (float32 rounding of a
#: unit vector is ~1e-7); counted, not failed.  Below -SAMPLER_HORIZON_TOL: below the horizon, a failure
SAMPLER_HORIZON_TOL = 1e-5
#: variance of f mu_i / pdf: a warning (not a failure) above this ratio to the reference sampler's
SAMPLER_VARIANCE_WARN = 2.0
SAMPLER_VARIANCE_N = 50_000
#: the reference sampler the variance is compared with
SAMPLER_REFERENCE = "eon"
#: u values at the corners of [0, 1)^2 added to every case (not histogrammed): NaN hunting
_U_EDGES = (0.0, 0.5, 1.0 - 2.0**-24)
#: surface: the materials and view directions; tolerances and why
SURFACE_MATERIALS = (
    {"base_color": (0.8, 0.5, 0.2), "base_diffuse_roughness": 0.5, "specular_roughness": 0.3},
    {"base_color": (0.9, 0.9, 0.9), "base_diffuse_roughness": 1.0, "specular_roughness": 0.6},
    {"base_color": (0.2, 0.6, 0.3), "base_diffuse_roughness": 0.0, "specular_roughness": 0.2, "specular_ior": 1.8},
)
SURFACE_MU = (0.1, 0.3, 0.6, 0.9)
SURFACE_WEIGHT_TOL = 5e-3
SURFACE_WEIGHT_REASON = (
    "albedo scaling is approximate by definition and each renderer has its own "
    "GGX albedo tables (ours: 2e-4; the viewer: a 4-sample estimate averaged over "
    "256 seeds): 5e-3 absolute on w*E, below the colour shift white-tint removes (~2e-2)"
)
SURFACE_PROB_TOL = 2e-2
SURFACE_PROB_REASON = (
    "any selection probability > 0 is unbiased; 0.02 flags a different selection rule, not table-level differences"
)


def QuantityGrade(  # noqa: N802 -- the constructor of a graded quantity, kept under its name
    quantity: str,
    passed: bool,
    max_abs_error: float,
    rms_error: float,
    tolerance: str,
    tolerance_reason: str,
    diagnosis: str | None = None,
    detail: str = "",
    n: int = 0,
    excluded: int = 0,
    grade: dict | None = None,
    where: str = "",
    sentence: str | None = None,
    checks: list | None = None,
    warnings: list | None = None,
    regions: Any = None,
    plot: Any = None,
    values: Any = None,
    measured: Any = None,
    threshold: Any = None,
) -> Result:
    """One graded quantity of one implementation (a row of the report's table): a
    :class:`~openpbr_diffuse.result.Result` of kind "quantity".

    ``where``: the inputs where the largest error occurs, in words; ``sentence``: the
    one-sentence diagnosis on the report's first screen (None: derived from ``diagnosis``);
    ``checks``: sub-checks with stable ids (Results as JSON, :func:`_sub_check`); ``regions``:
    per-case breakdown; ``plot``: data for the pictures; ``values``: the values'
    :class:`~openpbr_diffuse.conformance.grade.Grade` (the last two not serialised).

    >>> q = QuantityGrade("sampler pdf", False, 0.1, float("nan"), "|int pdf - 1| <= 0.005", "quadrature",
    ...                   diagnosis="pdf_not_normalised", measured=0.1, threshold=5e-3)
    >>> q.kind, q.verdict, q.status, q.finding
    ('quantity', 'fail', 'does not conform', 'pdf_not_normalised')
    """
    return Result(
        id="implementation." + quantity.replace(" ", "_"),
        quantity=quantity,
        kind="quantity",
        outcome="pass" if passed else "fail",
        measured=measured,
        threshold=threshold,
        max_abs_error=max_abs_error,
        rms_error=rms_error,
        tolerance=tolerance,
        tolerance_reason=tolerance_reason,
        diagnosis=diagnosis,
        detail=detail,
        n=n,
        excluded=excluded,
        grade=grade,
        where=where,
        sentence=sentence,
        checks=list(checks or ()),
        warnings=list(warnings or ()),
        regions=regions,
        plot=plot,
        values=values,
    )


def quantity_from_grade(quantity: str, g: Grade, excluded: int = 0, tolerance_reason: str | None = None) -> Result:
    """The graded quantity of a values grade (:func:`~openpbr_diffuse.conformance.grade.grade`):
    its largest error in tolerances against 1, its diagnosis, its rows.

    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> from openpbr_diffuse.conformance.deviations import DEVIATIONS
    >>> from openpbr_diffuse.conformance.grade import grade
    >>> v = default_vectors()
    >>> v = v.subset((v.model == "eon") & (v.kind == "brdf"))
    >>> q = quantity_from_grade("brdf", grade(v, DEVIATIONS["white_tint"](v)))
    >>> q.id, q.passed, q.finding, q.threshold
    ('implementation.brdf', False, 'white_tint', 1.0)
    """
    tol = f"|out - ref| <= {g.tolerance['absolute']:g} + {g.tolerance['relative']:g} |ref|"
    return QuantityGrade(
        quantity,
        bool(g.passed),
        float(g.max_abs_error),
        float(g.rms_error),
        tol,
        tolerance_reason or g.tolerance_reason,
        g.diagnosis,
        g.diagnosis_detail,
        g.n_rows,
        excluded,
        g.to_dict(),
        values=g,
        measured=g.measured,
        threshold=g.threshold,
    )


@dataclass
class ImplementationGrade:
    """Every graded quantity of one implementation, and what was run."""

    name: str
    model: str
    version: dict
    quantities: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return all(q.passed for q in self.quantities)

    def to_dict(self) -> dict:
        from ..conformance.grade import json_safe

        return json_safe(
            {
                "implementation": self.name,
                "model": self.model,
                "passed": self.passed,
                "version": self.version,
                "notes": self.notes,
                "quantities": [q.to_dict() for q in self.quantities],
            }
        )


def _tolerance_pair(tolerance):
    from ..conformance.grade import ABS_TOL, REL_TOL

    return (REL_TOL, ABS_TOL) if tolerance is None else tuple(tolerance)


def _failing_rows(rows, out, g):
    """Where the failing rows are: their count and, for albedo rows, their mu values."""
    from ..conformance.grade import accepted_reference

    ref = accepted_reference(rows, out, g.tolerance["absolute"])  # the albedo at mu = 0: 0 or the limit
    with np.errstate(invalid="ignore"):
        e = np.abs(out - ref) / (g.tolerance["absolute"] + g.tolerance["relative"] * np.abs(ref))
    bad = ~(np.nan_to_num(e, nan=np.inf).max(axis=1) <= 1.0)
    text = f"{int(bad.sum())} of {len(rows)} rows outside the tolerance"
    if np.all(rows.kind == "albedo") and bad.any():
        text += " (mu = " + ", ".join(f"{m:g}" for m in np.unique(rows.mu[bad])) + ")"
    return text


def grade_values(
    subject: Subject,
    vectors: VectorSet | None = None,
    kinds: Sequence[str] = ("brdf", "albedo"),
    precision: str | None = None,
) -> list[Result]:
    """BRDF / albedo of ``subject`` on the vectors of its model, graded by conformance.grade
    (``precision``: the precision the implementation declares, as ``grade``'s)."""
    from ..conformance.grade import grade
    from ..conformance.vectors import default_vectors

    vectors = default_vectors() if vectors is None else vectors
    results = []
    for kind in kinds:
        fn = subject.brdf if kind == "brdf" else subject.albedo
        rows = vectors.subset((vectors.kind == kind) & (vectors.model == subject.model))
        if fn is None or len(rows) == 0:
            continue
        excluded = 0
        domain = subject.brdf_domain if kind == "brdf" else subject.albedo_domain
        if domain is not None:
            inside = np.asarray(domain(rows.wi, rows.wo) if kind == "brdf" else domain(rows.mu), bool)
            excluded = int((~inside).sum())
            rows = rows.subset(inside)
        if kind == "brdf":
            out = fn(rows.wi, rows.wo, rows.roughness, rows.rho)
        else:
            out = fn(rows.mu, rows.roughness, rows.rho)
        tolerance, reason = subject.tolerance, subject.tolerance_reason
        if kind == "albedo" and "albedo_stderr" in subject.noise:
            # Monte Carlo albedo (Cycles): 4 standard errors of the noisiest row, measured
            se = float(np.max(subject.noise["albedo_stderr"]))
            rel, ab = _tolerance_pair(tolerance)
            tolerance = (rel, max(ab, 4.0 * se))
            reason = (
                f"rendered albedo: Monte Carlo standard error <= {se:.2g} (measured from the pixels); "
                f"tolerance 4 standard errors = {4 * se:.2g} absolute"
            )
        out = np.asarray(out, dtype=np.float64)
        g = grade(rows, out, model=subject.model, tolerance=tolerance, precision=precision)
        q = quantity_from_grade(kind, g, excluded, None if tolerance is None else reason)
        if not g.passed:
            q.detail += "; " + _failing_rows(rows, out, g)
        results.append(q)
    return results


def _sampler_nodes():
    """Unit directions (m, 3) and solid-angle weights (m,) of the (cos theta, phi) Gauss-Legendre
    rule, ordered bin by bin: node k lies in bin k // SAMPLER_NQ**2 (row-major over the bins)."""
    from .chi2 import _nodes

    z_edges = np.linspace(0.0, 1.0, SAMPLER_BINS[0] + 1)
    phi_edges = np.linspace(0.0, 2.0 * np.pi, SAMPLER_BINS[1] + 1)
    zn, zw = _nodes(z_edges, SAMPLER_NQ)
    pn, pw = _nodes(phi_edges, SAMPLER_NQ)
    shape = (zn.shape[0], pn.shape[0], SAMPLER_NQ, SAMPLER_NQ)
    Z = np.broadcast_to(zn[:, None, :, None], shape)
    P = np.broadcast_to(pn[None, :, None, :], shape)
    S = np.sqrt(np.clip(1.0 - Z * Z, 0.0, None))
    d = np.stack([S * np.cos(P), S * np.sin(P), Z], axis=-1).reshape(-1, 3)
    w = (zw[:, None, :, None] * pw[None, :, None, :]).reshape(-1)
    return d, w, z_edges, phi_edges


#: a node's pdf is "off" its closest reference strategy's by more than this relative amount
_BLAME_REL = 2e-2


def _pdf_blame(p_nodes: Any, WO: Any, WI: Any, R: Any, n_cases: int, m: int) -> str:
    """Where a pdf that does not integrate to 1 is off, against the reference strategy it
    matches best on most nodes (the lower quartile of the relative difference): "where the sampled mu_i < X (at every mu_o)" when the off nodes
    are the sampled directions below X at every view, "where mu_o < Y" when they are every
    direction at the views below Y; "" when neither (or no strategy is close)."""
    import openpbr_diffuse as od

    p = p_nodes.reshape(-1)
    ok = np.isfinite(p) & (p >= 0)
    best, best_med, ratio = None, np.inf, None
    for strategy in od.STRATEGIES:
        ref = od.pdf(strategy, WO, WI, R)
        with np.errstate(all="ignore"):
            rr = np.where(ok & (ref > SAMPLER_PDF_FLOOR), p / np.where(ref > 0, ref, 1.0), np.nan)
        # the lower quartile: a pdf off on up to 3/4 of the nodes still names its strategy
        med = float(np.nanpercentile(np.abs(rr - 1.0), 25)) if np.isfinite(rr).any() else np.inf
        if med < best_med:
            best, best_med, ratio = strategy, med, rr
    if ratio is None or best_med > SAMPLER_PDF_TOL:
        return ""
    off = np.abs(ratio - 1.0) > _BLAME_REL  # NaN (no comparison): not off
    if not off.any():
        return ""
    mu_i, mu_o = WI[:, 2], WO[:, 2]
    factor = float(np.nanmedian(ratio[off]))
    cases_off = off.reshape(n_cases, m).any(axis=1)
    x_i = float(mu_i[off].max())
    # mu_i: every view has off nodes, and no node above the largest off mu_i is off anywhere
    if cases_off.all() and not (off & (mu_i <= x_i)).all() and np.all(~off[mu_i > x_i]):
        lim = min((z for z in np.unique(mu_i) if z > x_i), default=1.0)
        return (
            f"the pdf is {factor:.3g}x the '{best}' strategy's where the sampled mu_i < {0.5 * (x_i + lim):.2g} "
            "(at every mu_o): the error follows the sampled direction, not the view"
        )
    x_o = float(mu_o[off].max())
    if not cases_off.all():
        return f"the pdf is {factor:.3g}x the '{best}' strategy's where mu_o <= {x_o:.2g} (for every sampled mu_i)"
    return ""


def _case_label(mu, r):
    return f"mu_o {mu:g}, roughness {r:g}"


def _sample_counts(wi, p):
    """Validity counts of sampled directions ``wi`` (n,3) and their pdf values ``p`` (n,)."""
    finite = np.all(np.isfinite(wi), axis=1)
    length = np.linalg.norm(np.where(finite[:, None], wi, 0.0), axis=1)
    below = finite & (wi[:, 2] < -SAMPLER_HORIZON_TOL)
    rounded = finite & (wi[:, 2] < 0.0) & ~below
    not_unit = finite & ~below & (np.abs(length - 1.0) > SAMPLER_UNIT_TOL)
    p_bad = finite & ~below & ~(np.isfinite(p) & (p >= 0.0))
    zero = finite & ~below & np.isfinite(p) & (p == 0.0)
    valid = finite & ~below & ~not_unit & ~p_bad
    return {
        "nan": int((~finite).sum()),
        "below_horizon": int(below.sum()),
        "horizon_rounding": int(rounded.sum()),
        "not_unit": int(not_unit.sum()),
        "pdf_not_finite_or_negative": int(p_bad.sum()),
        "pdf_zero": int(zero.sum()),
        "max_length_error": float(np.max(np.abs(length[finite & ~below] - 1.0), initial=0.0)),
        "valid": valid,
    }


@dataclass
class SamplerRun:
    """The subject's pdf at the quadrature nodes and its samples, from one batched call
    (:func:`run_sampler`); what every measurement of :func:`grade_sampler` reads."""

    #: the (mu_o, roughness) normalisation grid, ``SAMPLER_NORM_MU x SAMPLER_NORM_R``
    cases: list[tuple[float, float]]
    #: the view direction (len(cases), 3) and roughness (len(cases),) of each case
    wo: NDArray[np.float64]
    roughness: NDArray[np.float64]
    #: quadrature directions (m, 3) and solid-angle weights (m,), bin by bin (:func:`_sampler_nodes`)
    nodes: NDArray[np.float64]
    weights: NDArray[np.float64]
    z_edges: NDArray[np.float64]
    phi_edges: NDArray[np.float64]
    #: the pdf's inputs (len(cases) * m, 3 / 3 / -), case by case
    WO: NDArray[np.float64]
    WI: NDArray[np.float64]
    R: NDArray[np.float64]
    #: the pdf at those inputs, (len(cases), m)
    p_nodes: NDArray[np.float64]
    #: the index in ``cases`` of each ``SAMPLER_CASES`` case
    idx: list[int]
    #: the uniform numbers (len(SAMPLER_CASES) * per, 2): per case ``SAMPLER_SAMPLES`` random, then the corners
    U: NDArray[np.float64]
    per: int
    #: the sampled directions (len(SAMPLER_CASES), per, 3) and the pdf the sampler reports (len(SAMPLER_CASES), per)
    wi: NDArray[np.float64]
    p: NDArray[np.float64]

    @property
    def not_density(self) -> NDArray[np.bool_]:
        """(len(cases), m): nodes where the pdf is NaN, Inf or negative."""
        return ~(np.isfinite(self.p_nodes) & (self.p_nodes >= 0.0))


@dataclass
class SamplerFinding:
    """What one measurement of :func:`grade_sampler` found."""

    #: the sub-check: {"id", "status" (pass/fail/warn/info), "measured", "threshold", "detail", ...}
    check: dict[str, Any]
    #: the diagnosis code when the check fails, else None
    diagnosis: str | None = None
    #: what the grade's one-sentence diagnosis says of this measurement ("" when nothing)
    sentence: str = ""
    #: the inputs of the failure, in words ("" when it passes)
    where: str = ""
    #: per case {label: text}
    regions: dict[str, str] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    #: values later measurements or the report's pictures read (named in each measurement's docstring)
    data: dict[str, Any] = field(default_factory=dict)


def reference_sampler_subject(strategy: str, pdf_scale: float = 1.0) -> Subject:
    """A Python subject that samples with the library's reference ``strategy``
    (``openpbr_diffuse.STRATEGIES``) and reports that strategy's pdf times ``pdf_scale``: a
    conforming sampler (1, the default), or one whose pdf is off by a known factor.

    Examples
    --------
    >>> s = reference_sampler_subject("cosine", pdf_scale=1.1)
    >>> s.name, float(s.pdf(np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]), 0.5)[0] * np.pi)
    ('cosine (pdf x 1.1)', 1.1)
    """
    import openpbr_diffuse as od

    from .subject import Subject

    def sample(wo: ArrayLike, roughness: ArrayLike, u: ArrayLike) -> tuple[NDArray, NDArray]:
        return od.sample(strategy, wo, roughness, u)

    def pdf(wo: ArrayLike, wi: ArrayLike, roughness: ArrayLike) -> NDArray:
        return pdf_scale * od.pdf(strategy, wo, wi, roughness)

    name = strategy if pdf_scale == 1.0 else f"{strategy} (pdf x {pdf_scale:g})"
    return Subject(name, "eon", None, "", sample=sample, pdf=pdf)


def run_sampler(subject: Subject, seed: int = 12) -> SamplerRun:
    """Call the subject's pdf on every quadrature node of every (mu_o, roughness) case of
    ``SAMPLER_NORM_MU x SAMPLER_NORM_R`` (one call) and its sampler ``SAMPLER_SAMPLES`` times per
    ``SAMPLER_CASES`` case plus the corners ``_U_EDGES`` x ``_U_EDGES`` of [0, 1)^2 (one call);
    one shader run for both when ``subject.sample`` has ``combined`` (:func:`.glsl.sampler_functions`).

    Examples
    --------
    >>> run = run_sampler(reference_sampler_subject("cosine"))
    >>> run.p_nodes.shape, run.wi.shape == (len(SAMPLER_CASES), SAMPLER_SAMPLES + 9, 3)
    ((32, 8192), True)
    """
    if subject.sample is None or subject.pdf is None:
        raise ValueError(f"{subject.name}: a sampler is graded with both its sample and its pdf function")
    rng = np.random.default_rng(seed)
    cases = [(mu, r) for mu in SAMPLER_NORM_MU for r in SAMPLER_NORM_R]
    nodes, weights, z_edges, phi_edges = _sampler_nodes()
    m = nodes.shape[0]
    wo_c = np.stack([direction(mu, SAMPLER_PHI) for mu, _ in cases])
    r_c = np.array([r for _, r in cases])
    WO = np.repeat(wo_c, m, axis=0)
    WI = np.tile(nodes, (len(cases), 1))
    R = np.repeat(r_c, m)
    corners = np.array([(a, b) for a in _U_EDGES for b in _U_EDGES])
    per = SAMPLER_SAMPLES + corners.shape[0]
    idx = [cases.index(c) for c in SAMPLER_CASES]
    U = np.concatenate([np.concatenate([rng.random((SAMPLER_SAMPLES, 2)), corners]) for _ in SAMPLER_CASES])
    WO_s = np.repeat(wo_c[idx], per, axis=0)
    R_s = np.repeat(r_c[idx], per)
    combined = getattr(subject.sample, "combined", None)  # GLSL: both in one shader run
    if combined is not None:
        wi_all, p_all, p_nodes = combined(WO_s, R_s, U, WO, WI, R)
    else:
        p_nodes = subject.pdf(WO, WI, R)
        wi_all, p_all = subject.sample(WO_s, R_s, U)
    return SamplerRun(
        cases=cases,
        wo=wo_c,
        roughness=r_c,
        nodes=nodes,
        weights=weights,
        z_edges=z_edges,
        phi_edges=phi_edges,
        WO=WO,
        WI=WI,
        R=R,
        p_nodes=np.asarray(p_nodes, np.float64).reshape(len(cases), m),
        idx=idx,
        U=U,
        per=per,
        wi=np.asarray(wi_all, np.float64).reshape(len(SAMPLER_CASES), per, 3),
        p=np.asarray(p_all, np.float64).reshape(len(SAMPLER_CASES), per),
    )


def _sub_check(check_id: str, status: str, measured: Any, threshold: Any, detail: str) -> dict[str, Any]:
    """A sub-check with its stable id (``QuantityGrade.checks``): a Result as JSON."""
    return sub_check(check_id, status, measured, threshold, detail).to_dict()


def _normalisation_sentence(run: SamplerRun, mass: NDArray[np.float64], mass_err: NDArray[np.float64]) -> str:
    """The failure of ``sampler_pdf.normalisation`` in one sentence: the non-density values, or the
    worst integral, how many cases are off and where the pdf is off (:func:`_pdf_blame`)."""
    cases, m, bad_nodes = run.cases, run.nodes.shape[0], run.not_density
    if bad_nodes.any():
        k = int(np.argmax(bad_nodes.any(axis=1)))
        p_nodes = run.p_nodes
        n_nan, n_neg, n_inf = int(np.isnan(p_nodes).sum()), int((p_nodes < 0).sum()), int(np.isinf(p_nodes).sum())
        what = ", ".join(f"{c} {name}" for c, name in ((n_nan, "NaN"), (n_inf, "Inf"), (n_neg, "negative")) if c)
        return (
            f"pdf is not a density: {what} values at the {m * len(cases)} quadrature "
            f"directions (first at {_case_label(*cases[k])})"
        )
    k_worst = int(np.argmax(mass_err))
    mu_w, r_w = cases[k_worst]
    n_off = int((mass_err > SAMPLER_MASS_TOL).sum())
    off_mu = sorted({mu for (mu, _), e in zip(cases, mass_err) if e > SAMPLER_MASS_TOL})
    blame = _pdf_blame(run.p_nodes, run.WO, run.WI, run.R, len(cases), m)
    # "grazing" names the view, unless the error follows the sampled direction
    grazing = "grazing " if mu_w < 0.2 and "where the sampled mu_i" not in blame else ""
    sentence = f"pdf integrates to {mass[k_worst]:.4g} at {grazing}{_case_label(mu_w, r_w)}" + (
        f" ({n_off} of {len(cases)} (mu_o, roughness) cases off by more than "
        f"{SAMPLER_MASS_TOL:g}, at mu_o {off_mu[0]:g} to {off_mu[-1]:g})"
        if n_off > 1
        else ""
    )
    return sentence + (f"; {blame}" if blame else "")


def check_pdf_normalisation(run: SamplerRun) -> SamplerFinding:
    """``sampler_pdf.normalisation``: the integral of pdf(wo, ., roughness) over the upper hemisphere
    is 1 within ``SAMPLER_MASS_TOL`` at every (mu_o, roughness) of ``SAMPLER_NORM_MU x SAMPLER_NORM_R``,
    grazing views (mu_o < 0.2) included.

    The integral is the Gauss-Legendre rule in (cos theta, phi) of :func:`_sampler_nodes`
    (``SAMPLER_BINS`` bins of ``SAMPLER_NQ`` x ``SAMPLER_NQ`` nodes).  Threshold 5e-3: the rule
    integrates the reference strategies' pdfs to < 1e-5 over this grid and float32 pdf values add
    < 1e-6, so 5e-3 flags a pdf 0.5 % off and stays 20x below a 10 % error.  NaN, Inf or negative
    values at a node fail it (diagnosis ``pdf_not_finite``).  ``data``: ``mass`` (len(cases),) and
    ``bin_mass`` (len(cases), bins), the integrals the chi-square's expected counts come from.

    Examples
    --------
    >>> check_pdf_normalisation(run_sampler(reference_sampler_subject("cosine"))).check["status"]
    'pass'
    >>> f = check_pdf_normalisation(run_sampler(reference_sampler_subject("cosine", pdf_scale=1.1)))
    >>> f.check["status"], f.diagnosis, f.sentence.startswith("pdf integrates to 1.1 at ")
    ('fail', 'pdf_not_normalised', True)
    """
    cases, bad_nodes = run.cases, run.not_density
    nbins = SAMPLER_BINS[0] * SAMPLER_BINS[1]
    bin_mass = np.where(bad_nodes, 0.0, run.p_nodes * run.weights).reshape(len(cases), nbins, -1).sum(axis=2)
    mass = bin_mass.sum(axis=1)
    mass_err = np.where(bad_nodes.any(axis=1), np.inf, np.abs(mass - 1.0))
    ok = bool(np.all(mass_err <= SAMPLER_MASS_TOL))
    regions = {}
    for i, mu in enumerate(SAMPLER_NORM_MU):
        row = [mass[i * len(SAMPLER_NORM_R) + j] for j in range(len(SAMPLER_NORM_R))]
        regions[f"mu_o {mu:g}"] = (
            "integral of pdf "
            + " / ".join(f"{v:.4f}" for v in row)
            + " at roughness "
            + ", ".join(f"{r:g}" for r in SAMPLER_NORM_R)
        )
    data = {"mass": mass, "bin_mass": bin_mass}
    if ok:
        return SamplerFinding(
            check=_sub_check(
                "sampler_pdf.normalisation",
                "pass",
                float(mass_err.max()),
                SAMPLER_MASS_TOL,
                f"|integral of pdf - 1| <= {mass_err.max():.2g} over {len(cases)} (mu_o, roughness) cases",
            ),
            sentence=f"pdf integrates to 1 within {mass_err.max():.1g} at every (mu_o, roughness)",
            regions=regions,
            data=data,
        )
    sentence = _normalisation_sentence(run, mass, mass_err)
    k_worst = int(np.argmax(mass_err))
    return SamplerFinding(
        check=_sub_check("sampler_pdf.normalisation", "fail", float(mass_err.max()), SAMPLER_MASS_TOL, sentence),
        diagnosis="pdf_not_finite" if bad_nodes.any() else "pdf_not_normalised",
        sentence=sentence,
        where=f"{_case_label(*cases[k_worst])}: integral of pdf {mass[k_worst]:.4g}",
        regions=regions,
        data=data,
    )


def check_pdf_reference(run: SamplerRun, claim: str | None = None) -> SamplerFinding:
    """``sampler_pdf.reference``: the pdf at the quadrature nodes against every reference
    strategy's (``openpbr_diffuse.sampling.pdf``), max |pdf - ref| / max(ref, ``SAMPLER_PDF_FLOOR``).

    Matching a strategy means within ``SAMPLER_PDF_TOL`` (2e-3: float32 and llvmpipe arithmetic;
    the strategies differ from one another by > 10 % somewhere, so the closest is unambiguous);
    the floor keeps directions where the reference pdf is near 0 from turning float32 rounding
    into a large relative error.  A failure (diagnosis
    ``pdf_differs_from_<claim>``) only when ``claim`` names the strategy the sampler claims and its
    pdf differs; without a claim it is reported (status ``info``), not graded.  Nodes where the pdf
    is not a density are left out (the normalisation fails them).  ``check["by_strategy"]``: the
    error against each strategy.

    Examples
    --------
    The library's EON sampler: reported without a claim, graded against the one it claims:

    >>> run = run_sampler(reference_sampler_subject("eon"))
    >>> [check_pdf_reference(run, claim).check["status"] for claim in (None, "eon", "cosine")]
    ['info', 'pass', 'fail']
    >>> check_pdf_reference(run, "cosine").sentence.endswith("(it matches 'eon')")
    True
    """
    import openpbr_diffuse as od

    ok = ~run.not_density.reshape(-1)
    ref_err = {}
    for strategy in od.STRATEGIES:
        ref = od.pdf(strategy, run.WO[ok], run.WI[ok], run.R[ok])
        ref_err[strategy] = float(
            np.max(np.abs(run.p_nodes.reshape(-1)[ok] - ref) / np.maximum(ref, SAMPLER_PDF_FLOOR), initial=0.0)
        )
    best = min(ref_err, key=ref_err.__getitem__)
    matches = ref_err[best] <= SAMPLER_PDF_TOL
    detail = (
        f"matches the reference '{best}' strategy's pdf to {ref_err[best]:.2g} relative"
        if matches
        else f"matches no reference strategy's pdf (closest '{best}', {ref_err[best]:.2g})"
    )
    if best != "eon":
        detail += f"; differs from the reference 'eon' pdf by up to {ref_err['eon']:.2g} relative"
    if claim is None:
        detail += " (no sampler model claimed: reported, not graded)"
        sentence = (
            f"matches the reference '{best}' strategy's pdf"
            + (f" (not the 'eon' one: relative difference up to {ref_err['eon']:.2g})" if best != "eon" else "")
            if matches
            else f"matches no reference strategy's pdf (closest '{best}', {ref_err[best]:.2g} relative)"
        )
        check = _sub_check("sampler_pdf.reference", "info", ref_err["eon"], SAMPLER_PDF_TOL, detail)
        return SamplerFinding(check={**check, "by_strategy": ref_err}, sentence=sentence)
    claim_ok = ref_err[claim] <= SAMPLER_PDF_TOL
    detail = (
        f"claimed '{claim}': "
        + (
            f"matches to {ref_err[claim]:.2g} relative"
            if claim_ok
            else f"differs by up to {ref_err[claim]:.2g} relative"
        )
        + "; "
        + detail
    )
    check = _sub_check("sampler_pdf.reference", "pass" if claim_ok else "fail", ref_err[claim], SAMPLER_PDF_TOL, detail)
    if claim_ok:
        sentence = f"matches the claimed '{claim}' pdf to {ref_err[claim]:.2g} relative"
        return SamplerFinding(check={**check, "by_strategy": ref_err}, sentence=sentence)
    sentence = f"pdf differs from the reference '{claim}' pdf by up to {ref_err[claim]:.2g} relative" + (
        f" (it matches '{best}')" if matches else ""
    )
    return SamplerFinding(
        check={**check, "by_strategy": ref_err}, diagnosis=f"pdf_differs_from_{claim}", sentence=sentence
    )


#: the validity counts that fail the sampler, their words and their diagnosis
_INVALID = {
    "nan": ("NaN/Inf", "samples_not_finite"),
    "below_horizon": (f"below the horizon (z < -{SAMPLER_HORIZON_TOL:g})", "samples_below_horizon"),
    "not_unit": ("not unit vectors", "samples_not_unit"),
    "pdf_not_finite_or_negative": ("with a NaN/Inf/negative pdf", "pdf_not_finite"),
}


def check_sample_validity(run: SamplerRun) -> SamplerFinding:
    """``sampler_chi2.valid``: every sampled direction is finite, a unit vector to
    ``SAMPLER_UNIT_TOL`` and above the horizon, and its reported pdf is finite and >= 0.

    Threshold 0: any such sample fails, counted and named with the u that produced the first.
    z in [-``SAMPLER_HORIZON_TOL``, 0) is float32 rounding of a direction on the horizon (~1e-7 for
    a unit vector): counted, not failed (f = 0 there); a pdf of 0 is counted too (a renderer
    discards the sample).  The u values include the corners 0, 0.5 and 1 - 2^-24 of [0, 1)^2,
    where NaNs hide.  ``data["valid"]``: (len(SAMPLER_CASES), per) the valid samples.

    Examples
    --------
    Cosine samples mirrored below the horizon where u.x = 0.5 (three u corners per case):

    >>> from dataclasses import replace
    >>> cosine = reference_sampler_subject("cosine")
    >>> def below(wo, r, u):
    ...     wi, p = cosine.sample(wo, r, u)
    ...     return wi * np.where(u[:, :1] == 0.5, [1, 1, -1], 1), p
    >>> f = check_sample_validity(run_sampler(replace(cosine, sample=below)))
    >>> f.check["status"], f.diagnosis, f.check["counts"]["below_horizon"] >= 3 * len(SAMPLER_CASES)
    ('fail', 'samples_below_horizon', True)
    """
    counts: dict[str, Any] = {}
    first_bad: str | None = None
    valid = []
    for c, (mu, r) in enumerate(SAMPLER_CASES):
        wi, p = run.wi[c], run.p[c]
        cnt = _sample_counts(wi, p)
        valid.append(cnt.pop("valid"))
        for key, v in cnt.items():
            counts[key] = max(counts.get(key, 0.0), v) if key == "max_length_error" else counts.get(key, 0) + v
        if first_bad is None and not valid[-1].all():
            j = int(np.argmin(valid[-1]))
            u = run.U[c * run.per + j]
            first_bad = (
                f"first at {_case_label(mu, r)}, u = ({u[0]:.8g}, {u[1]:.8g}): "
                f"wi = ({', '.join(f'{x:.4g}' for x in wi[j])}), pdf {p[j]:.4g}"
            )
    invalid = sum(counts[k] for k in _INVALID)
    n_total = run.U.shape[0]
    named = [
        f"{counts[k]} {label}" + (f" (|wi| off by up to {counts['max_length_error']:.2g})" if k == "not_unit" else "")
        for k, (label, _) in _INVALID.items()
        if counts[k]
    ]
    detail = (
        f"{', '.join(named)} of {n_total} samples ({first_bad})"
        if named
        else f"all {n_total} samples finite, unit and above the horizon (u corners included)"
    )
    if counts["horizon_rounding"]:
        detail += (
            f"; {counts['horizon_rounding']} on the horizon rounded below it "
            f"(-{SAMPLER_HORIZON_TOL:g} <= z < 0; f = 0 there: not a failure)"
        )
    if counts["pdf_zero"]:
        detail += f"; {counts['pdf_zero']} samples with pdf 0 (discarded by a renderer)"
    check = {**_sub_check("sampler_chi2.valid", "fail" if invalid else "pass", invalid, 0, detail), "counts": counts}
    data = {"valid": np.stack(valid)}
    if not invalid:
        return SamplerFinding(check=check, data=data)
    return SamplerFinding(
        check=check,
        diagnosis=_INVALID[next(k for k in _INVALID if counts[k])][1],
        sentence=f"the sampler returns {', '.join(named)} of {n_total} samples ({first_bad})",
        where=str(first_bad),
        data=data,
    )


def check_sample_chi2(run: SamplerRun, normalisation: SamplerFinding, validity: SamplerFinding) -> SamplerFinding:
    """``sampler_chi2.chi2``: do the samples follow the pdf the sampler reports?

    Pearson chi-square (``sampling.quality.pearson_chi2``, the project's one harness; sparse bins
    pooled) of the valid random samples of each ``SAMPLER_CASES`` case, binned over
    ``SAMPLER_BINS`` (cos theta, phi) bins, against n times the pdf's integral over each bin
    (``normalisation.data["bin_mass"]``; ``validity.data["valid"]``).  Threshold: the smallest
    p-value >= the Sidak-corrected ``SAMPLER_ALPHA`` over the cases, so a correct sampler fails
    with probability ``SAMPLER_ALPHA`` in all.  When the pdf does not integrate to 1 at the worst
    case, the sentence also gives p against the pdf rescaled to 1.  ``data["plot"]``: per case the
    observed and expected counts (the report's histograms).

    Examples
    --------
    Cosine samples reported with the uniform strategy's pdf:

    >>> from dataclasses import replace
    >>> s = replace(reference_sampler_subject("cosine"), pdf=reference_sampler_subject("uniform").pdf)
    >>> run = run_sampler(s)
    >>> f = check_sample_chi2(run, check_pdf_normalisation(run), check_sample_validity(run))
    >>> f.check["status"], f.diagnosis, f.check["measured"] < f.check["threshold"]
    ('fail', 'samples_do_not_follow_pdf', True)
    """
    from ..sampling.quality import pearson_chi2
    from .chi2 import histogram

    mass, bin_mass, valid = normalisation.data["mass"], normalisation.data["bin_mass"], validity.data["valid"]
    n = SAMPLER_SAMPLES
    sidak = 1.0 - (1.0 - SAMPLER_ALPHA) ** (1.0 / len(SAMPLER_CASES))
    tests, regions, plot = [], {}, []
    for c, (mu, r) in enumerate(SAMPLER_CASES):
        rnd = valid[c][:n]
        d = run.wi[c][:n][rnd]
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        d[:, 2] = np.maximum(d[:, 2], 0.0)  # rounded just below the horizon: the first bin
        observed = histogram(d, run.z_edges, run.phi_edges)
        k = run.idx[c]
        expected = rnd.sum() * bin_mass[k].reshape(SAMPLER_BINS)
        pval, chi2, dof = pearson_chi2(observed, expected)
        p_norm = pearson_chi2(observed, expected / mass[k])[0] if mass[k] > 0 else float("nan")
        tests.append({"mu_o": mu, "roughness": r, "p": pval, "chi2": chi2, "dof": dof, "p_normalised": p_norm, "k": k})
        regions[_case_label(mu, r)] = f"chi2 p = {pval:.3g} ({int(rnd.sum())} samples, {dof} dof)"
        plot.append({"mu_o": mu, "roughness": r, "observed": observed, "expected": expected, "p": pval})
    t = min(tests, key=lambda t: t["p"])
    label = _case_label(t["mu_o"], t["roughness"])
    detail = f"min p = {t['p']:.3g} at {label} over {len(tests)} cases (Sidak threshold {sidak:.2g})"
    data = {"plot": plot}
    if t["p"] >= sidak:
        check = _sub_check("sampler_chi2.chi2", "pass", t["p"], sidak, detail)
        sentence = f"samples follow the pdf (min chi² p = {t['p']:.2g} over {len(tests)} cases)"
        return SamplerFinding(check=check, sentence=sentence, regions=regions, data=data)
    sentence = (
        f"samples do not follow the pdf (chi² p = {t['p']:.2g}, chi² = {t['chi2']:.4g} on {t['dof']} dof, at {label})"
    )
    if abs(mass[t["k"]] - 1.0) > SAMPLER_MASS_TOL:
        sentence += (
            f"; the pdf integrates to {mass[t['k']]:.4g} there (against it rescaled to 1: p = {t['p_normalised']:.2g})"
        )
    return SamplerFinding(
        check=_sub_check("sampler_chi2.chi2", "fail", t["p"], sidak, detail),
        diagnosis="samples_do_not_follow_pdf",
        sentence=sentence,
        where=f"{label}: chi2 p = {t['p']:.3g}",
        regions=regions,
        data=data,
    )


def _brdf_at_samples(subject: Subject, run: SamplerRun, ref_wi: NDArray[np.float64]) -> tuple[Any, Any, str]:
    """f (rho = 1, first channel) at the subject's first ``SAMPLER_VARIANCE_N`` samples per case and
    at the reference sampler's ``ref_wi``, in one BRDF call: the subject's f, else the reference
    model's.  Returns (f theirs (cases, nv), f reference (cases, nv), whose f in words)."""
    from ..models import evaluate

    nc, nv = ref_wi.shape[:2]
    their_wi = np.nan_to_num(run.wi[:, :nv], nan=0.0, posinf=0.0, neginf=0.0)
    f_wi = np.concatenate([their_wi.reshape(-1, 3), ref_wi.reshape(-1, 3)])
    f_wo = np.concatenate([np.repeat(run.wo[run.idx], nv, axis=0)] * 2)
    f_r = np.concatenate([np.repeat(run.roughness[run.idx], nv)] * 2)
    ones = np.ones((f_wi.shape[0], 3))
    if subject.brdf is not None:
        f_all = np.asarray(subject.brdf(f_wi, f_wo, f_r, ones), np.float64)[:, 0]
        whose = "their f"
    else:
        model = subject.model if subject.model in ("eon", "fon", "eon_approx", "lambert") else "eon"
        f_all = evaluate(model, f_wi, f_wo, f_r, ones)[:, 0]
        whose = "the reference f (no BRDF function given)"
    return f_all[: nc * nv].reshape(nc, nv), f_all[nc * nv :].reshape(nc, nv), whose


def check_sample_variance(subject: Subject, run: SamplerRun, seed: int = 12) -> SamplerFinding:
    """``sampler_chi2.variance``: the variance of the estimator f mu_i / pdf with the subject's
    sampler over that with the reference ``SAMPLER_REFERENCE`` sampler, per ``SAMPLER_CASES`` case.

    f is the subject's at rho = 1 when it has a BRDF function, else the reference model's; both
    samplers are weighted by the same f, over ``SAMPLER_VARIANCE_N`` samples each (the reference
    sampler's drawn with seed ``seed + 1 + case``).  Threshold: a warning, not a failure, above
    ``SAMPLER_VARIANCE_WARN`` (2x): a noisier sampler is still unbiased -- cosine sampling is
    several times noisier than EON's at grazing view (Portsmouth, Kutz and Hill, JCGT 2025,
    Fig. 10-12).  Samples that are invalid or have pdf 0 contribute 0.

    Examples
    --------
    >>> s = reference_sampler_subject("eon")
    >>> f = check_sample_variance(s, run_sampler(s))
    >>> f.check["status"], 0.8 < f.check["measured"] < 1.25, f.warnings
    ('pass', True, [])
    """
    import openpbr_diffuse as od

    nv = min(SAMPLER_SAMPLES, SAMPLER_VARIANCE_N)
    ref = [
        od.sample_rng(SAMPLER_REFERENCE, run.wo[k], run.roughness[k], seed + 1 + c, shape=(nv,))
        for c, k in enumerate(run.idx)
    ]
    ref_wi, ref_p = np.stack([w for w, _ in ref]), np.stack([p for _, p in ref])
    f_theirs, f_ref, whose = _brdf_at_samples(subject, run, ref_wi)
    ratios, regions, warnings = [], {}, []
    for c, (mu, r) in enumerate(SAMPLER_CASES):
        pt, zt = run.p[c, :nv], run.wi[c, :nv, 2]
        good = np.isfinite(pt) & (pt > 0) & np.isfinite(zt) & (zt > 0)
        wt = np.where(good, f_theirs[c] * np.where(good, zt, 0.0) / np.where(good, pt, 1.0), 0.0)
        wr = np.where(
            ref_p[c] > 0, f_ref[c] * np.maximum(ref_wi[c, :, 2], 0.0) / np.where(ref_p[c] > 0, ref_p[c], 1.0), 0.0
        )
        vt, vr = float(np.var(wt)), float(np.var(wr))
        ratio = vt / vr if vr > 1e-12 else (1.0 if vt <= 1e-12 else math.inf)
        ratios.append(ratio)
        if ratio > SAMPLER_VARIANCE_WARN:
            warnings.append(
                f"variance of f mu_i / pdf is {ratio:.3g}x the reference '{SAMPLER_REFERENCE}' "
                f"sampler's at {_case_label(mu, r)}"
            )
        regions[_case_label(mu, r)] = (
            f"variance of f mu_i / pdf {vt:.3g} vs {vr:.3g} for '{SAMPLER_REFERENCE}' (ratio {ratio:.3g}); "
            f"mean {wt.mean():.4f} vs {wr.mean():.4f}"
        )
    c = max(range(len(ratios)), key=ratios.__getitem__)
    worst, label = ratios[c], _case_label(*SAMPLER_CASES[c])
    detail = (
        f"variance of f mu_i / pdf ({whose}) at most {worst:.3g}x the reference "
        f"'{SAMPLER_REFERENCE}' sampler's (at {label}); a warning above {SAMPLER_VARIANCE_WARN:g}x, not a failure"
    )
    check = _sub_check("sampler_chi2.variance", "warn" if warnings else "pass", worst, SAMPLER_VARIANCE_WARN, detail)
    sentence = (
        f"warning: the variance of f mu_i / pdf is {worst:.3g}x the reference '{SAMPLER_REFERENCE}' sampler's at {label}"
        if warnings
        else ""
    )
    return SamplerFinding(check=check, sentence=sentence, regions=regions, warnings=warnings)


def _first_failure(*findings: SamplerFinding) -> SamplerFinding | None:
    return next((f for f in findings if f.diagnosis is not None), None)


def _sampler_pdf_grade(
    run: SamplerRun, normalisation: SamplerFinding, reference: SamplerFinding, claim: str | None
) -> Result:
    """``"sampler pdf"``: normalisation, then agreement with the reference strategies."""
    failed = _first_failure(normalisation, reference)
    return QuantityGrade(
        quantity="sampler pdf",
        passed=failed is None,
        max_abs_error=float(normalisation.check["measured"]),
        rms_error=float("nan"),
        tolerance=f"|integral of pdf - 1| <= {SAMPLER_MASS_TOL:g}"
        + (f"; pdf vs '{claim}' relative {SAMPLER_PDF_TOL:g}" if claim else ""),
        tolerance_reason="quadrature error < 1e-5 on the reference pdfs, float32 values; 20x below a 10 % error",
        diagnosis=None if failed is None else failed.diagnosis,
        detail=f"{normalisation.check['detail']}; {reference.check['detail']}",
        n=run.p_nodes.size,
        where=normalisation.where,
        sentence=f"{normalisation.sentence} and {reference.sentence}" if failed is None else failed.sentence,
        checks=[normalisation.check, reference.check],
        regions=normalisation.regions,
    )


def _sampler_chi2_grade(
    run: SamplerRun, chi2: SamplerFinding, validity: SamplerFinding, variance: SamplerFinding
) -> Result:
    """``"sampler chi2"``: validity of the samples, then the chi-square; the variance warns."""
    failed = _first_failure(validity, chi2)
    checks = [chi2.check, validity.check, variance.check]
    if failed is None:
        sentence = chi2.sentence + (f"; {variance.sentence}" if variance.warnings else "")
    else:
        sentence = failed.sentence
    return QuantityGrade(
        quantity="sampler chi2",
        passed=failed is None,
        max_abs_error=float("nan"),
        rms_error=float("nan"),
        tolerance=f"p >= {chi2.check['threshold']:.2g} (Sidak, alpha {SAMPLER_ALPHA}); "
        "no NaN / below-horizon / non-unit sample",
        tolerance_reason=f"chi-square of its samples against its own pdf over {SAMPLER_BINS[0]} x {SAMPLER_BINS[1]} "
        "(cos theta, phi) bins (sparse bins pooled)",
        diagnosis=None if failed is None else failed.diagnosis,
        detail="; ".join(c["detail"] for c in checks),
        n=run.U.shape[0],
        sentence=sentence,
        checks=checks,
        where="" if failed is None else failed.where,
        warnings=variance.warnings,
        regions={label: f"{text}; {variance.regions[label]}" for label, text in chi2.regions.items()},
        plot={"cases": chi2.data["plot"], "z_edges": run.z_edges, "phi_edges": run.phi_edges},
    )


def grade_sampler(subject: Subject, quick: bool = False, seed: int = 12, claim: str | None = None) -> list[Result]:
    """Grade a subject's sampler and pdf: normalisation, chi-square, reference pdf, variance.

    Five measurements, each a sub-check with a stable id (the function that measures it says
    what, with which threshold and why):

    - ``sampler_pdf.normalisation`` (:func:`check_pdf_normalisation`): the integral of
      ``pdf(wo, ., roughness)`` over the upper hemisphere is 1 within ``SAMPLER_MASS_TOL`` at every
      (mu_o, roughness) of ``SAMPLER_NORM_MU x SAMPLER_NORM_R``; NaN, Inf or negative pdf values at
      the quadrature nodes fail it.
    - ``sampler_pdf.reference`` (:func:`check_pdf_reference`): the pdf at those nodes against every
      reference strategy's (``openpbr_diffuse.sampling.pdf``), relative to max(reference,
      ``SAMPLER_PDF_FLOOR``); a failure only when ``claim`` names the strategy the sampler claims
      to implement.
    - ``sampler_chi2.chi2`` (:func:`check_sample_chi2`): Pearson chi-square of ``SAMPLER_SAMPLES``
      samples per ``SAMPLER_CASES`` case against n times the pdf's integral over each (cos theta,
      phi) bin; Sidak-corrected ``SAMPLER_ALPHA``.
    - ``sampler_chi2.valid`` (:func:`check_sample_validity`): samples that are NaN/Inf, below the
      horizon, not unit vectors, or whose pdf is NaN/negative, counted and named (any fails); u
      includes the corners 0 and 1 - 2^-24 of [0, 1)^2.
    - ``sampler_chi2.variance`` (:func:`check_sample_variance`): the variance of f mu_i / pdf over
      the reference ``eon`` sampler's with the same f: a warning, not a failure, above
      ``SAMPLER_VARIANCE_WARN``.

    Every call of the subject's code is batched (:func:`run_sampler`): one pdf call (all nodes of
    all cases), one sample call (all samples) -- one shader run for both when ``subject.sample``
    has ``combined`` (:func:`.glsl.sampler_functions`) -- and one BRDF call (f at theirs and at the
    reference sampler's samples).

    Parameters
    ----------
    subject : Subject
        With ``sample(wo, roughness, u) -> (wi, pdf)`` and ``pdf(wo, wi, roughness)``; without
        them nothing is graded ([] is returned).
    quick : bool
        Accepted for callers' convenience; the sample count is ``SAMPLER_SAMPLES`` either way
        (the same in ``check`` and ``report``).
    seed : int
        Seed of the uniform numbers.
    claim : str, optional
        The reference strategy (``openpbr_diffuse.STRATEGIES``) the sampler claims to be.

    Returns
    -------
    list of QuantityGrade
        ``"sampler pdf"`` (normalisation, reference) and ``"sampler chi2"`` (chi-square, validity,
        variance), each with ``sentence`` (one-sentence diagnosis), ``checks`` and ``regions``.

    Examples
    --------
    A Python subject: cosine-weighted sampling with its exact pdf conforms (its pdf is the
    reference "cosine" strategy's, not "eon"'s), and the same samples with a uniform pdf do not:

    >>> import numpy as np, openpbr_diffuse as od
    >>> from openpbr_diffuse.graders.subject import Subject
    >>> def sample(wo, r, u):
    ...     return od.sample("cosine", wo, 0.0, u)
    >>> def pdf(wo, wi, r):
    ...     return od.pdf("cosine", wo, wi, 0.0)
    >>> good = Subject("cosine", "eon", None, "", sample=sample, pdf=pdf)
    >>> q_pdf, q_chi = grade_sampler(good, quick=True)
    >>> q_pdf.passed, q_chi.passed, q_pdf.checks[1]["detail"].startswith("matches the reference 'cosine'")
    (True, True, True)
    >>> bad = Subject("mixed", "eon", None, "", sample=sample,
    ...               pdf=lambda wo, wi, r: np.full(len(wi), 1 / (2 * np.pi)))
    >>> q_pdf, q_chi = grade_sampler(bad, quick=True)
    >>> q_pdf.passed, q_chi.passed, q_chi.diagnosis
    (True, False, 'samples_do_not_follow_pdf')
    """
    import openpbr_diffuse as od

    if subject.sample is None or subject.pdf is None:
        return []
    if claim is not None and claim not in od.STRATEGIES:
        raise ValueError(f"claim: expected one of {', '.join(od.STRATEGIES)}, got {claim!r}")
    run = run_sampler(subject, seed)
    normalisation = check_pdf_normalisation(run)
    reference = check_pdf_reference(run, claim)
    validity = check_sample_validity(run)
    chi2 = check_sample_chi2(run, normalisation, validity)
    variance = check_sample_variance(subject, run, seed)
    return [
        _sampler_pdf_grade(run, normalisation, reference, claim),
        _sampler_chi2_grade(run, chi2, validity, variance),
    ]


def surface_reference(material: dict, wo: ArrayLike, selection: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(w*E (n,3), probability (n,)) of the diffuse lobe of ``OpenPBRSurface``."""
    from ..nodes import OpenPBRSurface

    surface = OpenPBRSurface(**material, selection=selection)
    lobe = next(lobe for lobe in surface.lobes(wo) if lobe.name == "diffuse")
    return np.asarray(lobe.weight * lobe.albedo, float), np.asarray(lobe.probability, float)


def grade_surface(subject: Subject, selection: str) -> list[Result]:
    """Diffuse weight x albedo and selection probability inside the surface, vs OpenPBRSurface."""
    if subject.surface is None:
        return []
    wo = direction(np.array(SURFACE_MU), SAMPLER_PHI)
    # per material, then concatenated
    got_w: Any = []
    got_p: Any = []
    ref_w: Any = []
    ref_p: Any = []
    cand: dict[str, Any] = {"white_tint": [], "selection_other": []}
    other = "length" if selection == "max" else "max"
    for material in SURFACE_MATERIALS:
        res = subject.surface(material, wo)
        got_w.append(res["weight_albedo"])
        got_p.append(res["probability"])
        w, p = surface_reference(material, wo, selection)
        ref_w.append(w)
        ref_p.append(p)
        # white tint: the lobe's albedo at white (= 1 for EON) times base_color
        white = {**material, "base_color": (1.0, 1.0, 1.0)}
        ww, _ = surface_reference(white, wo, selection)
        cand["white_tint"].append(ww * np.asarray(material["base_color"]))
        cand["selection_other"].append(surface_reference(material, wo, other)[1])
    got_w, got_p, ref_w, ref_p = map(np.concatenate, (got_w, got_p, ref_w, ref_p))
    cand = {k: np.concatenate(v) for k, v in cand.items()}

    def q(name, got, ref, tol, reason, candidates):
        err = np.abs(got - ref)
        passed = bool(np.all(err <= tol))
        diagnosis, detail = None, "conforms: every value within the tolerance"
        if not passed:
            fits = {k: float(np.max(np.abs(got - c))) for k, c in candidates.items()}
            best = min(fits, key=fits.get) if fits else None
            if best is not None and fits[best] <= tol:
                diagnosis = best
                detail = f"explained by {best} (max deviation {fits[best]:.3g} from that prediction)"
            else:
                detail = "no known deviation explains it; closest: " + ", ".join(
                    f"{k} ({v:.3g})" for k, v in sorted(fits.items(), key=lambda kv: kv[1])
                )
        return QuantityGrade(
            name,
            passed,
            float(err.max()),
            float(np.sqrt(np.mean(err**2))),
            f"absolute {tol:g}",
            reason,
            diagnosis,
            detail,
            n=int(got.shape[0]),
        )

    return [
        q(
            "surface weight x albedo",
            got_w,
            ref_w,
            SURFACE_WEIGHT_TOL,
            SURFACE_WEIGHT_REASON,
            {"white_tint": cand["white_tint"]},
        ),
        q(
            f"surface probability ({selection})",
            got_p,
            ref_p,
            SURFACE_PROB_TOL,
            SURFACE_PROB_REASON,
            {f"selection_{other}": cand["selection_other"]},
        ),
    ]


def grade_properties(subject: Subject) -> list[Result]:
    """The properties of the subject's own BRDF and albedo functions
    (:func:`openpbr_diffuse.conformance.properties.check_properties`) as one quantity,
    ``"properties"``, whose ``checks`` are the properties (ids ``property.*``).

    Not run (``[]``) without a BRDF or albedo function, or for a subject whose values are
    Monte Carlo estimates or that documents a restricted input domain (a property's
    directions may lie outside it).

    Examples
    --------
    >>> import openpbr_diffuse as od
    >>> from openpbr_diffuse.graders.subject import Subject
    >>> s = Subject("ref", "eon", None, "", brdf=lambda wi, wo, r, rho: od.evaluate("eon", wi, wo, r, rho))
    >>> [q] = grade_properties(s)
    >>> q.quantity, q.passed, q.checks[0]["id"]
    ('properties', True, 'property.reciprocity')
    """
    from ..conformance.properties import check_properties

    if (
        (subject.brdf is None and subject.albedo is None)
        or subject.noise
        or subject.brdf_domain
        or subject.albedo_domain
    ):
        return []
    checks = check_properties(subject.brdf, subject.albedo, model=subject.model, tolerance=subject.tolerance)
    failed = [c for c in checks if c["status"] == "fail"]
    n_run = sum(c["status"] != "skip" for c in checks)
    sentence = (
        "; ".join(c["detail"] for c in failed)
        if failed
        else f"all {n_run} properties hold (reciprocity, energy, channels, rho, horizon, r = 0, clamps, azimuth)"
    )
    return [
        QuantityGrade(
            "properties",
            not failed,
            float("nan"),
            float("nan"),
            "each property's own (see its check)",
            "properties of the implementation's own functions: a failure names the kind of mistake",
            failed[0]["id"] if failed else None,
            sentence,
            n=len(checks),
            sentence=sentence,
            checks=checks,
        )
    ]


def grade_subject(
    subject: Subject,
    *,
    vectors: VectorSet | None = None,
    quick: bool = False,
    quantities: Sequence[str] = ("brdf", "albedo", "properties", "sampler", "surface"),
    selection: str | None = None,
    sampler_model: str | None = None,
    precision: str | None = None,
) -> ImplementationGrade:
    """Grade every quantity ``subject`` offers; returns an :class:`ImplementationGrade`.

    ``sampler_model`` names the reference strategy the sampler claims to implement (e.g.
    ``"eon"``): its pdf must then match that strategy's (see :func:`grade_sampler`).
    """
    result = ImplementationGrade(subject.name, subject.model, dict(subject.version), notes=list(subject.notes))
    if getattr(subject, "paths", None):  # one subject per code path (light type): each graded, quantities named by path
        for label, path in subject.paths:
            for q in grade_subject(
                path, vectors=vectors, quick=quick, quantities=quantities, selection=selection
            ).quantities:
                q.quantity = f"{q.quantity} {label}"
                result.quantities.append(q)
        return result
    kinds = tuple(k for k in ("brdf", "albedo") if k in quantities)
    result.quantities += grade_values(subject, vectors, kinds, precision)
    if "properties" in quantities:
        result.quantities += grade_properties(subject)
    if "sampler" in quantities:
        result.quantities += grade_sampler(subject, quick=quick, claim=sampler_model)
    if "surface" in quantities and subject.surface is not None:
        result.quantities += grade_surface(subject, selection or getattr(subject, "selection", "length") or "length")
    return result
