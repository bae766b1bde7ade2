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
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

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


@dataclass
class QuantityGrade:
    """One graded quantity of one implementation (a row of the report's table)."""

    quantity: str
    passed: bool
    max_abs_error: float
    rms_error: float
    tolerance: str
    tolerance_reason: str
    diagnosis: str | None = None
    detail: str = ""
    n: int = 0
    excluded: int = 0
    grade: dict | None = None
    #: the inputs where the largest error occurs, in words
    where: str = ""
    #: the one-sentence diagnosis shown on the report's first screen (None: derived from ``diagnosis``)
    sentence: str | None = None
    #: sub-checks with stable ids: [{"id", "status" (pass/fail/warn/info), "measured", "threshold", "detail"}]
    checks: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    #: per-case breakdown {label: text}
    regions: dict | None = None
    #: data for the report's pictures (not serialised)
    plot: Any = field(default=None, repr=False, compare=False)
    #: the values' :class:`~openpbr_diffuse.conformance.grade.Grade` (printed as ``check FILE`` prints it; not serialised)
    values: Any = field(default=None, repr=False, compare=False)

    @classmethod
    def from_grade(
        cls, quantity: str, g: Grade, excluded: int = 0, tolerance_reason: str | None = None
    ) -> QuantityGrade:
        tol = f"|out - ref| <= {g.tolerance['absolute']:g} + {g.tolerance['relative']:g} |ref|"
        q = cls(
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
        )
        q.values = g
        return q


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
                "quantities": [
                    {k: v for k, v in asdict(q).items() if k not in ("plot", "values")} for q in self.quantities
                ],
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
) -> list[QuantityGrade]:
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
        q = QuantityGrade.from_grade(kind, g, excluded, None if tolerance is None else reason)
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


def grade_sampler(
    subject: Subject, quick: bool = False, seed: int = 12, claim: str | None = None
) -> list[QuantityGrade]:
    """Grade a subject's sampler and pdf: normalisation, chi-square, reference pdf, variance.

    Four measurements, each a sub-check with a stable id:

    - ``sampler_pdf.normalisation``: the integral of ``pdf(wo, ., roughness)`` over the upper
      hemisphere is 1 within ``SAMPLER_MASS_TOL`` at every (mu_o, roughness) of
      ``SAMPLER_NORM_MU x SAMPLER_NORM_R`` (Gauss-Legendre in (cos theta, phi), 16 x 32 bins of
      4 x 4 nodes); NaN, Inf or negative pdf values at the nodes fail it.
    - ``sampler_pdf.reference``: the pdf at those nodes against every reference strategy's
      (``openpbr_diffuse.sampling.pdf``), relative to max(reference, ``SAMPLER_PDF_FLOOR``); a
      failure only when ``claim`` names the strategy the sampler claims to implement.
    - ``sampler_chi2.chi2``: Pearson chi-square (``sampling.quality.pearson_chi2``, the project's one
      harness) of ``SAMPLER_N`` samples per ``SAMPLER_CASES`` case binned over (cos theta, phi)
      against n times the pdf's integral over each bin; Sidak-corrected ``SAMPLER_ALPHA``.
    - ``sampler_chi2.valid``: samples that are NaN/Inf, below the horizon (z < 0), not unit
      vectors, or whose pdf is NaN/negative, counted and named (any fails; z in
      [-``SAMPLER_HORIZON_TOL``, 0) is float32 rounding of a horizon direction, counted only); u
      includes the corners 0 and 1 - 2^-24 of [0, 1)^2.
    - ``sampler_chi2.variance``: the variance of f mu_i / pdf (the subject's f at rho = 1, else the
      reference model's; the subject's sampler) over the reference ``eon`` sampler's with the same
      f: a warning, not a failure, above ``SAMPLER_VARIANCE_WARN``.

    Every call of the subject's code is batched: one pdf call (all nodes of all cases), one sample
    call (all samples) -- one shader run for both when ``subject.sample`` has ``combined``
    (:func:`.glsl.sampler_functions`) -- and one BRDF call (f at theirs and at the reference
    sampler's samples).

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

    from ..models import evaluate
    from ..sampling.quality import pearson_chi2
    from .chi2 import histogram

    if subject.sample is None or subject.pdf is None:
        return []
    if claim is not None and claim not in od.STRATEGIES:
        raise ValueError(f"claim: expected one of {', '.join(od.STRATEGIES)}, got {claim!r}")
    rng = np.random.default_rng(seed)
    n = SAMPLER_SAMPLES
    cases = [(mu, r) for mu in SAMPLER_NORM_MU for r in SAMPLER_NORM_R]
    nodes, weights, z_edges, phi_edges = _sampler_nodes()
    m = nodes.shape[0]
    nbins = SAMPLER_BINS[0] * SAMPLER_BINS[1]

    # (a) the pdf on every node of every case: one call
    wo_c = np.stack([direction(mu, SAMPLER_PHI) for mu, _ in cases])
    r_c = np.array([r for _, r in cases])
    WO = np.repeat(wo_c, m, axis=0)
    WI = np.tile(nodes, (len(cases), 1))
    R = np.repeat(r_c, m)
    # (b) the samples' inputs: random u, then the corners of [0, 1)^2, per case
    corners = np.array([(a, b) for a in _U_EDGES for b in _U_EDGES])
    per = n + corners.shape[0]
    idx = [cases.index(c) for c in SAMPLER_CASES]
    U = np.concatenate([np.concatenate([rng.random((n, 2)), corners]) for _ in SAMPLER_CASES])
    WO_s = np.repeat(wo_c[idx], per, axis=0)
    R_s = np.repeat(r_c[idx], per)
    combined = getattr(subject.sample, "combined", None)  # GLSL: both in one shader run
    if combined is not None:
        wi_all, p_all, p_nodes = combined(WO_s, R_s, U, WO, WI, R)
    else:
        p_nodes = subject.pdf(WO, WI, R)
        wi_all, p_all = subject.sample(WO_s, R_s, U)
    p_nodes = np.asarray(p_nodes, np.float64).reshape(len(cases), m)
    bad_nodes = ~(np.isfinite(p_nodes) & (p_nodes >= 0.0))
    bin_mass = np.where(bad_nodes, 0.0, p_nodes * weights).reshape(len(cases), nbins, -1).sum(axis=2)
    mass = bin_mass.sum(axis=1)
    mass_err = np.where(bad_nodes.any(axis=1), np.inf, np.abs(mass - 1.0))
    k_worst = int(np.argmax(mass_err))
    norm_ok = bool(np.all(mass_err <= SAMPLER_MASS_TOL))
    n_off = int((mass_err > SAMPLER_MASS_TOL).sum())
    mu_w, r_w = cases[k_worst]
    grazing = "grazing " if mu_w < 0.2 else ""
    if bad_nodes.any():
        k = int(np.argmax(bad_nodes.any(axis=1)))
        n_nan = int(np.isnan(p_nodes).sum())
        n_neg = int((p_nodes < 0).sum())
        n_inf = int(np.isinf(p_nodes).sum())
        what = ", ".join(f"{c} {name}" for c, name in ((n_nan, "NaN"), (n_inf, "Inf"), (n_neg, "negative")) if c)
        norm_sentence = (
            f"pdf is not a density: {what} values at the {m * len(cases)} quadrature "
            f"directions (first at {_case_label(*cases[k])})"
        )
    else:
        off_mu = sorted({mu for (mu, _), e in zip(cases, mass_err) if e > SAMPLER_MASS_TOL})
        blame = _pdf_blame(p_nodes, WO, WI, R, len(cases), m)
        if "where the sampled mu_i" in blame:
            grazing = ""  # the error follows the sampled direction, not the view
        norm_sentence = f"pdf integrates to {mass[k_worst]:.4g} at {grazing}{_case_label(mu_w, r_w)}" + (
            f" ({n_off} of {len(cases)} (mu_o, roughness) cases off by more than "
            f"{SAMPLER_MASS_TOL:g}, at mu_o {off_mu[0]:g} to {off_mu[-1]:g})"
            if n_off > 1
            else ""
        )
        if blame:
            norm_sentence += f"; {blame}"
    # (c) against every reference strategy at the same nodes
    ok = ~bad_nodes.reshape(-1)
    ref_err = {}
    for strategy in od.STRATEGIES:
        ref = od.pdf(strategy, WO[ok], WI[ok], R[ok])
        ref_err[strategy] = float(
            np.max(np.abs(p_nodes.reshape(-1)[ok] - ref) / np.maximum(ref, SAMPLER_PDF_FLOOR), initial=0.0)
        )
    best = min(ref_err, key=ref_err.__getitem__)
    matches = ref_err[best] <= SAMPLER_PDF_TOL
    ref_detail = (
        f"matches the reference '{best}' strategy's pdf to {ref_err[best]:.2g} relative"
        if matches
        else f"matches no reference strategy's pdf (closest '{best}', {ref_err[best]:.2g})"
    )
    if best != "eon":
        ref_detail += f"; differs from the reference 'eon' pdf by up to {ref_err['eon']:.2g} relative"
    if claim is not None:
        ref_ok = ref_err[claim] <= SAMPLER_PDF_TOL
        ref_status = "pass" if ref_ok else "fail"
        ref_detail = (
            f"claimed '{claim}': "
            + (
                f"matches to {ref_err[claim]:.2g} relative"
                if ref_ok
                else f"differs by up to {ref_err[claim]:.2g} relative"
            )
            + "; "
            + ref_detail
        )
    else:
        ref_ok, ref_status = True, "info"
        ref_detail += " (no sampler model claimed: reported, not graded)"
    pdf_checks: list[dict[str, Any]] = [
        {
            "id": "sampler_pdf.normalisation",
            "status": "pass" if norm_ok else "fail",
            "measured": float(mass_err.max()),
            "threshold": SAMPLER_MASS_TOL,
            "detail": (
                f"|integral of pdf - 1| <= {mass_err.max():.2g} over {len(cases)} (mu_o, roughness) cases"
                if norm_ok
                else norm_sentence
            ),
        },
        {
            "id": "sampler_pdf.reference",
            "status": ref_status,
            "measured": ref_err[claim if claim else "eon"],
            "threshold": SAMPLER_PDF_TOL,
            "detail": ref_detail,
            "by_strategy": ref_err,
        },
    ]
    if not norm_ok:
        pdf_diag, pdf_sentence = ("pdf_not_finite" if bad_nodes.any() else "pdf_not_normalised"), norm_sentence
    elif not ref_ok:
        pdf_diag = f"pdf_differs_from_{claim}"
        pdf_sentence = f"pdf differs from the reference '{claim}' pdf by up to {ref_err[claim]:.2g} relative" + (  # type: ignore[index]  # not ref_ok: a claim
            f" (it matches '{best}')" if matches else ""
        )
    else:
        pdf_diag = None
        pdf_sentence = f"pdf integrates to 1 within {mass_err.max():.1g} at every (mu_o, roughness) and "
        if claim is not None:
            pdf_sentence += f"matches the claimed '{claim}' pdf to {ref_err[claim]:.2g} relative"
        elif matches:
            pdf_sentence += f"matches the reference '{best}' strategy's pdf" + (
                f" (not the 'eon' one: relative difference up to {ref_err['eon']:.2g})" if best != "eon" else ""
            )
        else:
            pdf_sentence += f"matches no reference strategy's pdf (closest '{best}', {ref_err[best]:.2g} relative)"
    regions = {}
    for i, mu in enumerate(SAMPLER_NORM_MU):
        row = [mass[i * len(SAMPLER_NORM_R) + j] for j in range(len(SAMPLER_NORM_R))]
        regions[f"mu_o {mu:g}"] = (
            "integral of pdf "
            + " / ".join(f"{v:.4f}" for v in row)
            + " at roughness "
            + ", ".join(f"{r:g}" for r in SAMPLER_NORM_R)
        )
    q_pdf = QuantityGrade(
        "sampler pdf",
        bool(norm_ok and ref_ok),
        float(mass_err.max()),
        float("nan"),
        f"|integral of pdf - 1| <= {SAMPLER_MASS_TOL:g}"
        + (f"; pdf vs '{claim}' relative {SAMPLER_PDF_TOL:g}" if claim else ""),
        "quadrature error < 1e-5 on the reference pdfs, float32 values; 20x below a 10 % error",
        pdf_diag,
        f"{pdf_checks[0]['detail']}; {ref_detail}",
        n=m * len(cases),
        where=(f"{_case_label(mu_w, r_w)}: integral of pdf {mass[k_worst]:.4g}" if not norm_ok else ""),
        sentence=pdf_sentence,
        checks=pdf_checks,
        regions=regions,
    )

    wi_all = np.asarray(wi_all, np.float64).reshape(len(SAMPLER_CASES), per, 3)
    p_all = np.asarray(p_all, np.float64).reshape(len(SAMPLER_CASES), per)
    # (d) f at their samples and at the reference sampler's: one BRDF call
    nv = min(n, SAMPLER_VARIANCE_N)
    ref_wi: Any = []  # per case, then stacked
    ref_p: Any = []
    for c, k in enumerate(idx):
        w, pr = od.sample_rng(SAMPLER_REFERENCE, wo_c[k], r_c[k], seed + 1 + c, shape=(nv,))
        ref_wi.append(w)
        ref_p.append(pr)
    ref_wi, ref_p = np.stack(ref_wi), np.stack(ref_p)
    their_wi = np.nan_to_num(wi_all[:, :nv], nan=0.0, posinf=0.0, neginf=0.0)
    f_wi = np.concatenate([their_wi.reshape(-1, 3), ref_wi.reshape(-1, 3)])
    f_wo = np.concatenate([np.repeat(wo_c[idx], nv, axis=0)] * 2)
    f_r = np.concatenate([np.repeat(r_c[idx], nv)] * 2)
    ones = np.ones((f_wi.shape[0], 3))
    if subject.brdf is not None:
        f_all = np.asarray(subject.brdf(f_wi, f_wo, f_r, ones), np.float64)[:, 0]
        f_whose = "their f"
    else:
        f_all = evaluate(
            subject.model if subject.model in ("eon", "fon", "eon_approx", "lambert") else "eon", f_wi, f_wo, f_r, ones
        )[:, 0]
        f_whose = "the reference f (no BRDF function given)"
    f_theirs = f_all[: len(idx) * nv].reshape(len(idx), nv)
    f_ref = f_all[len(idx) * nv :].reshape(len(idx), nv)

    sidak = 1.0 - (1.0 - SAMPLER_ALPHA) ** (1.0 / len(SAMPLER_CASES))
    counts_total: dict[str, Any] = {}
    first_bad: str | None = None
    tests, warnings, chi_regions, plot = [], [], {}, []
    for c, (mu, r) in enumerate(SAMPLER_CASES):
        wi, p = wi_all[c], p_all[c]
        cnt = _sample_counts(wi, p)
        valid = cnt.pop("valid")
        for key, v in cnt.items():
            if key == "max_length_error":
                counts_total[key] = max(counts_total.get(key, 0.0), v)
            else:
                counts_total[key] = counts_total.get(key, 0) + v
        if first_bad is None and not valid.all():
            j = int(np.argmin(valid))
            first_bad = (
                f"first at {_case_label(mu, r)}, u = ({U[c * per + j, 0]:.8g}, {U[c * per + j, 1]:.8g}): "
                f"wi = ({', '.join(f'{x:.4g}' for x in wi[j])}), pdf {p[j]:.4g}"
            )
        rnd = valid[:n]
        d = wi[:n][rnd]
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        d[:, 2] = np.maximum(d[:, 2], 0.0)  # rounded just below the horizon: the first bin
        observed = histogram(d, z_edges, phi_edges)
        k = idx[c]
        expected = rnd.sum() * bin_mass[k].reshape(SAMPLER_BINS)
        pval, chi2, dof = pearson_chi2(observed, expected)
        p_norm = pearson_chi2(observed, expected / mass[k])[0] if mass[k] > 0 else float("nan")
        tests.append(
            {
                "mu_o": mu,
                "roughness": r,
                "p": pval,
                "chi2": chi2,
                "dof": dof,
                "p_normalised": p_norm,
                "n": int(rnd.sum()),
            }
        )
        # variance of f mu_i / pdf, theirs and the reference sampler's with the same f
        pt, zt = p[:nv], wi[:nv, 2]
        good = np.isfinite(pt) & (pt > 0) & np.isfinite(zt) & (zt > 0)
        wt = np.where(good, f_theirs[c] * np.where(good, zt, 0.0) / np.where(good, pt, 1.0), 0.0)
        wr = np.where(
            ref_p[c] > 0, f_ref[c] * np.maximum(ref_wi[c, :, 2], 0.0) / np.where(ref_p[c] > 0, ref_p[c], 1.0), 0.0
        )
        vt, vr = float(np.var(wt)), float(np.var(wr))
        ratio = vt / vr if vr > 1e-12 else (1.0 if vt <= 1e-12 else math.inf)
        tests[-1].update(
            {
                "variance": vt,
                "variance_reference": vr,
                "variance_ratio": ratio,
                "mean": float(wt.mean()),
                "mean_reference": float(wr.mean()),
            }
        )
        if ratio > SAMPLER_VARIANCE_WARN:
            warnings.append(
                f"variance of f mu_i / pdf is {ratio:.3g}x the reference '{SAMPLER_REFERENCE}' "
                f"sampler's at {_case_label(mu, r)}"
            )
        chi_regions[_case_label(mu, r)] = (
            f"chi2 p = {pval:.3g} ({int(rnd.sum())} samples, {dof} dof); variance of f mu_i / pdf {vt:.3g} "
            f"vs {vr:.3g} for '{SAMPLER_REFERENCE}' (ratio {ratio:.3g}); mean {wt.mean():.4f} vs {wr.mean():.4f}"
        )
        plot.append({"mu_o": mu, "roughness": r, "observed": observed, "expected": expected, "p": pval})
    pmin_t = min(tests, key=lambda t: t["p"])
    chi_ok = pmin_t["p"] >= sidak
    invalid = sum(counts_total[k] for k in ("nan", "below_horizon", "not_unit", "pdf_not_finite_or_negative"))
    n_total = per * len(SAMPLER_CASES)
    named = [
        f"{counts_total[k]} {label}"
        for k, label in (
            ("nan", "NaN/Inf"),
            ("below_horizon", f"below the horizon (z < -{SAMPLER_HORIZON_TOL:g})"),
            ("not_unit", f"not unit vectors (|wi| off by up to {counts_total['max_length_error']:.2g})"),
            ("pdf_not_finite_or_negative", "with a NaN/Inf/negative pdf"),
        )
        if counts_total[k]
    ]
    valid_detail = (
        f"{', '.join(named)} of {n_total} samples ({first_bad})"
        if named
        else f"all {n_total} samples finite, unit and above the horizon (u corners included)"
    )
    if counts_total["horizon_rounding"]:
        valid_detail += (
            f"; {counts_total['horizon_rounding']} on the horizon rounded below it "
            f"(-{SAMPLER_HORIZON_TOL:g} <= z < 0; f = 0 there: not a failure)"
        )
    if counts_total["pdf_zero"]:
        valid_detail += f"; {counts_total['pdf_zero']} samples with pdf 0 (discarded by a renderer)"
    worst_var = max(tests, key=lambda t: t["variance_ratio"])
    chi_checks = [
        {
            "id": "sampler_chi2.chi2",
            "status": "pass" if chi_ok else "fail",
            "measured": pmin_t["p"],
            "threshold": sidak,
            "detail": f"min p = {pmin_t['p']:.3g} at {_case_label(pmin_t['mu_o'], pmin_t['roughness'])} "
            f"over {len(tests)} cases (Sidak threshold {sidak:.2g})",
        },
        {
            "id": "sampler_chi2.valid",
            "status": "fail" if invalid else "pass",
            "measured": invalid,
            "threshold": 0,
            "detail": valid_detail,
            "counts": counts_total,
        },
        {
            "id": "sampler_chi2.variance",
            "status": "warn" if warnings else "pass",
            "measured": worst_var["variance_ratio"],
            "threshold": SAMPLER_VARIANCE_WARN,
            "detail": (
                f"variance of f mu_i / pdf ({f_whose}) at most {worst_var['variance_ratio']:.3g}x the reference "
                f"'{SAMPLER_REFERENCE}' sampler's (at {_case_label(worst_var['mu_o'], worst_var['roughness'])}); "
                f"a warning above {SAMPLER_VARIANCE_WARN:g}x, not a failure"
            ),
        },
    ]
    if invalid:
        key = next(k for k in ("nan", "below_horizon", "not_unit", "pdf_not_finite_or_negative") if counts_total[k])
        diag = {
            "nan": "samples_not_finite",
            "below_horizon": "samples_below_horizon",
            "not_unit": "samples_not_unit",
            "pdf_not_finite_or_negative": "pdf_not_finite",
        }[key]
        sentence = f"the sampler returns {', '.join(named)} of {n_total} samples ({first_bad})"
    elif not chi_ok:
        diag = "samples_do_not_follow_pdf"
        sentence = (
            f"samples do not follow the pdf (chi² p = {pmin_t['p']:.2g}, chi² = {pmin_t['chi2']:.4g} "
            f"on {pmin_t['dof']} dof, at {_case_label(pmin_t['mu_o'], pmin_t['roughness'])})"
        )
        k = cases.index((pmin_t["mu_o"], pmin_t["roughness"]))
        if abs(mass[k] - 1.0) > SAMPLER_MASS_TOL:
            sentence += (
                f"; the pdf integrates to {mass[k]:.4g} there (against it rescaled to 1: "
                f"p = {pmin_t['p_normalised']:.2g})"
            )
    else:
        diag = None
        sentence = f"samples follow the pdf (min chi² p = {pmin_t['p']:.2g} over {len(tests)} cases)"
        if warnings:
            sentence += (
                f"; warning: the variance of f mu_i / pdf is {worst_var['variance_ratio']:.3g}x the "
                f"reference '{SAMPLER_REFERENCE}' sampler's at "
                f"{_case_label(worst_var['mu_o'], worst_var['roughness'])}"
            )
    q_chi = QuantityGrade(
        "sampler chi2",
        bool(chi_ok and not invalid),
        float("nan"),
        float("nan"),
        f"p >= {sidak:.2g} (Sidak, alpha {SAMPLER_ALPHA}); no NaN / below-horizon / non-unit sample",
        f"chi-square of its samples against its own pdf over {SAMPLER_BINS[0]} x {SAMPLER_BINS[1]} "
        "(cos theta, phi) bins (sparse bins pooled)",
        diag,
        "; ".join(c["detail"] for c in chi_checks),
        n=n_total,
        sentence=sentence,
        checks=chi_checks,
        where=(
            first_bad  # type: ignore[arg-type]  # set when a sample is invalid
            if invalid
            else (
                f"{_case_label(pmin_t['mu_o'], pmin_t['roughness'])}: chi2 p = {pmin_t['p']:.3g}" if not chi_ok else ""
            )
        ),
        warnings=warnings,
        regions=chi_regions,
        plot={"cases": plot, "z_edges": z_edges, "phi_edges": phi_edges},
    )
    return [q_pdf, q_chi]


def surface_reference(material: dict, wo: ArrayLike, selection: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(w*E (n,3), probability (n,)) of the diffuse lobe of ``OpenPBRSurface``."""
    from ..nodes import OpenPBRSurface

    surface = OpenPBRSurface(**material, selection=selection)
    lobe = next(lobe for lobe in surface.lobes(wo) if lobe.name == "diffuse")
    return np.asarray(lobe.weight * lobe.albedo, float), np.asarray(lobe.probability, float)


def grade_surface(subject: Subject, selection: str) -> list[QuantityGrade]:
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


def grade_properties(subject: Subject) -> list[QuantityGrade]:
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
