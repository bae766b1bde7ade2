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

from dataclasses import asdict, dataclass, field

import numpy as np

from ._arrays import direction

#: sampler: (mu_o, r) configurations, phi_o off the x axis (the LTC frame is exercised)
SAMPLER_CASES = tuple((mu, r) for mu in (0.05, 0.3, 0.8) for r in (0.5, 1.0))
SAMPLER_PHI = 0.7
SAMPLER_N = {True: 40_000, False: 200_000}
SAMPLER_ALPHA = 0.01
#: agreement of a sampler's reported pdf with a reference strategy's (float32 + llvmpipe)
SAMPLER_PDF_TOL = 2e-3
#: surface: the materials and view directions; tolerances and why
SURFACE_MATERIALS = (
    {"base_color": (0.8, 0.5, 0.2), "base_diffuse_roughness": 0.5, "specular_roughness": 0.3},
    {"base_color": (0.9, 0.9, 0.9), "base_diffuse_roughness": 1.0, "specular_roughness": 0.6},
    {"base_color": (0.2, 0.6, 0.3), "base_diffuse_roughness": 0.0, "specular_roughness": 0.2,
     "specular_ior": 1.8},
)
SURFACE_MU = (0.1, 0.3, 0.6, 0.9)
SURFACE_WEIGHT_TOL = 5e-3
SURFACE_WEIGHT_REASON = ("albedo scaling is approximate by definition and each renderer has its own "
                         "GGX albedo tables (ours: 2e-4; the viewer: a 4-sample estimate averaged over "
                         "256 seeds): 5e-3 absolute on w*E, below the colour shift white-tint removes (~2e-2)")
SURFACE_PROB_TOL = 2e-2
SURFACE_PROB_REASON = ("any selection probability > 0 is unbiased; 0.02 flags a different selection "
                       "rule, not table-level differences")


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

    @classmethod
    def from_grade(cls, quantity, g, excluded=0, tolerance_reason=None):
        tol = f"|out - ref| <= {g.tolerance['absolute']:g} + {g.tolerance['relative']:g} |ref|"
        return cls(quantity, bool(g.passed), float(g.max_abs_error), float(g.rms_error), tol,
                   tolerance_reason or g.tolerance_reason, g.diagnosis, g.diagnosis_detail, g.n_rows,
                   excluded, g.to_dict())


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

        return json_safe({"implementation": self.name, "model": self.model, "passed": self.passed,
                      "version": self.version, "notes": self.notes,
                      "quantities": [asdict(q) for q in self.quantities]})


def _tolerance_pair(tolerance):
    from ..conformance.grade import ABS_TOL, REL_TOL

    return (REL_TOL, ABS_TOL) if tolerance is None else tuple(tolerance)


def _failing_rows(rows, out, g):
    """Where the failing rows are: their count and, for albedo rows, their mu values."""
    from ..conformance.deviations import reference

    ref = reference(rows)
    with np.errstate(invalid="ignore"):
        e = np.abs(out - ref) / (g.tolerance["absolute"] + g.tolerance["relative"] * np.abs(ref))
    bad = ~(np.nan_to_num(e, nan=np.inf).max(axis=1) <= 1.0)
    text = f"{int(bad.sum())} of {len(rows)} rows outside the tolerance"
    if np.all(rows.kind == "albedo") and bad.any():
        text += " (mu = " + ", ".join(f"{m:g}" for m in np.unique(rows.mu[bad])) + ")"
    return text


def grade_values(subject, vectors=None, kinds=("brdf", "albedo")) -> list[QuantityGrade]:
    """BRDF / albedo of ``subject`` on the vectors of its model, graded by conformance.grade."""
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
            reason = (f"rendered albedo: Monte Carlo standard error <= {se:.2g} (measured from the pixels); "
                      f"tolerance 4 standard errors = {4 * se:.2g} absolute")
        out = np.asarray(out, dtype=np.float64)
        g = grade(rows, out, model=subject.model, tolerance=tolerance)
        q = QuantityGrade.from_grade(kind, g, excluded, None if tolerance is None else reason)
        if not g.passed:
            q.detail += "; " + _failing_rows(rows, out, g)
        results.append(q)
    return results


def grade_sampler(subject, quick=False, seed=12) -> list[QuantityGrade]:
    """The sampler's reported pdf against the reference strategies, and chi-square of its samples."""
    import openpbr_diffuse as od

    from .chi2 import chi2_test

    if subject.sample is None or subject.pdf is None:
        return []
    rng = np.random.default_rng(seed)
    n = SAMPLER_N[bool(quick)]
    worst = {s: 0.0 for s in od.STRATEGIES}
    tests = []
    self_err = 0.0
    for mu, r in SAMPLER_CASES:
        wo1 = direction(mu, SAMPLER_PHI)
        wo = np.broadcast_to(wo1, (n, 3))
        rough = np.full(n, r)
        wi, pdf = subject.sample(wo, rough, rng.random((n, 2)))
        wi, pdf = np.asarray(wi, float), np.asarray(pdf, float)
        ok = pdf > 0
        m = min(n, 4000)
        own = np.asarray(subject.pdf(wo[:m], wi[:m], rough[:m]), float)
        self_err = max(self_err, float(np.max(np.abs(own - pdf[:m]) / np.maximum(pdf[:m], 1e-6))))
        for s in od.STRATEGIES:
            ref = od.pdf(s, wo[ok], wi[ok], rough[ok])
            worst[s] = max(worst[s], float(np.max(np.abs(pdf[ok] - ref) / np.maximum(ref, 1e-3))))

        def own_pdf(d, wo1=wo1, r=r):
            k = d.shape[0]
            return subject.pdf(np.broadcast_to(wo1, (k, 3)), d, np.full(k, r))

        tests.append((mu, r, chi2_test(wi[ok], own_pdf)))
    best = min(worst, key=worst.get)
    q_pdf = QuantityGrade(
        "sampler pdf", bool(worst[best] <= SAMPLER_PDF_TOL and self_err <= SAMPLER_PDF_TOL),
        float(worst[best]), float("nan"), f"relative {SAMPLER_PDF_TOL:g}",
        "float32 / llvmpipe pdf arithmetic; the strategies differ by > 10 % somewhere",
        None if best == "eon" else f"strategy_{best}",
        f"reported pdf matches the reference strategy '{best}' to {worst[best]:.2g} relative "
        f"(vs 'eon': {worst['eon']:.2g}); sample pdf vs its own pdf(): {self_err:.2g}",
        n=len(SAMPLER_CASES) * n)
    sidak = 1.0 - (1.0 - SAMPLER_ALPHA) ** (1.0 / len(tests))
    pmin = min(t[2]["p"] for t in tests)
    outside = sum(t[2]["outside"] for t in tests)
    mass = max(abs(t[2]["mass"] - 1.0) for t in tests)
    q_chi = QuantityGrade(
        "sampler chi2", bool(pmin >= sidak and outside == 0), float("nan"), float("nan"),
        f"p >= {sidak:.2g} (Sidak, alpha {SAMPLER_ALPHA})",
        "chi-square of its samples against its own pdf over 16 x 32 (cos theta, phi) bins",
        None if pmin >= sidak else "samples_do_not_follow_pdf",
        f"min p = {pmin:.3g} over {len(tests)} (mu_o, r) cases; {outside} samples below the horizon; "
        f"|pdf mass - 1| <= {mass:.2g}", n=len(SAMPLER_CASES) * n)
    return [q_pdf, q_chi]


def surface_reference(material, wo, selection):
    """(w*E (n,3), probability (n,)) of the diffuse lobe of ``OpenPBRSurface``."""
    from ..nodes import OpenPBRSurface

    surface = OpenPBRSurface(**material, selection=selection)
    lobe = next(lobe for lobe in surface.lobes(wo) if lobe.name == "diffuse")
    return np.asarray(lobe.weight * lobe.albedo, float), np.asarray(lobe.probability, float)


def grade_surface(subject, selection) -> list[QuantityGrade]:
    """Diffuse weight x albedo and selection probability inside the surface, vs OpenPBRSurface."""
    if subject.surface is None:
        return []
    wo = direction(np.array(SURFACE_MU), SAMPLER_PHI)
    got_w, got_p, ref_w, ref_p, cand = [], [], [], [], {"white_tint": [], "selection_other": []}
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
                detail = ("no known deviation explains it; closest: "
                          + ", ".join(f"{k} ({v:.3g})" for k, v in sorted(fits.items(), key=lambda kv: kv[1])))
        return QuantityGrade(name, passed, float(err.max()), float(np.sqrt(np.mean(err ** 2))),
                             f"absolute {tol:g}", reason, diagnosis, detail, n=int(got.shape[0]))

    return [q("surface weight x albedo", got_w, ref_w, SURFACE_WEIGHT_TOL, SURFACE_WEIGHT_REASON,
              {"white_tint": cand["white_tint"]}),
            q(f"surface probability ({selection})", got_p, ref_p, SURFACE_PROB_TOL, SURFACE_PROB_REASON,
              {f"selection_{other}": cand["selection_other"]})]


def grade_subject(subject, *, vectors=None, quick=False, quantities=("brdf", "albedo", "sampler", "surface"),
                  selection=None) -> ImplementationGrade:
    """Grade every quantity ``subject`` offers; returns an :class:`ImplementationGrade`."""
    result = ImplementationGrade(subject.name, subject.model, dict(subject.version), notes=list(subject.notes))
    if getattr(subject, "paths", None):  # one subject per code path (light type): each graded, quantities named by path
        for label, path in subject.paths:
            for q in grade_subject(path, vectors=vectors, quick=quick, quantities=quantities,
                                   selection=selection).quantities:
                q.quantity = f"{q.quantity} {label}"
                result.quantities.append(q)
        return result
    kinds = tuple(k for k in ("brdf", "albedo") if k in quantities)
    result.quantities += grade_values(subject, vectors, kinds)
    if "sampler" in quantities:
        result.quantities += grade_sampler(subject, quick=quick)
    if "surface" in quantities and subject.surface is not None:
        result.quantities += grade_surface(subject, selection or getattr(subject, "selection", "length"))
    return result
