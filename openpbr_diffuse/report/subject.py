"""The implementation under test: graded first, shown on the report's first screen.

:func:`grade_under_test` grades what the user gave -- a filled vectors file (graded with
``conformance.grade.grade``) or a :class:`~openpbr_diffuse.graders.subject.Subject` (their
GLSL / C++ / a registered implementation, graded with ``graders.grading.grade_subject``) --
and returns an :class:`UnderTest`: one verdict per quantity (BRDF, albedo, sampler pdf,
sampler chi-square), each "conforms", "does not conform" or "could not run", with the
diagnosis in one sentence, the largest error and the inputs where it occurs.  When a
subject can be called, :func:`figures` draws its error maps over (mu_i, mu_o), its in-plane
lobe slices over the reference's, its albedo curves and its sampler's histogram against
its pdf (matplotlib, Agg).

These verdicts are never mixed with the library's own evidence (the report's sections).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..result import CONFORMS, CONFORMS_WITH_WARNINGS, COULD_NOT_RUN, DOES_NOT_CONFORM, Result, sub_check

if TYPE_CHECKING:
    from ..graders.subject import Subject

#: The sentence when a failure matches no known deviation.
NO_KNOWN = "no known deviation explains this"
#: Exit status of ``report`` when the implementation could not be run.
EXIT_COULD_NOT_RUN = 3
_QUANTITY_LABEL = {
    "brdf": "BRDF",
    "albedo": "albedo",
    "properties": "properties",
    "sampler pdf": "pdf",
    "sampler chi2": "sampler",
}


def Verdict(  # noqa: N802 -- the constructor of a quantity's verdict, kept under its name
    quantity: str, status: str, diagnosis: str | None = None, sentence: str = "", **fields: Any
) -> Result:
    """One quantity's verdict on the report's first screen: a :class:`~openpbr_diffuse.result.Result`
    of kind "quantity" whose ``status`` is its tier ("conforms", "conforms with warnings", "does
    not conform") or "could not run"; id ``implementation.<quantity>``; ``fields``: any other
    field of the Result (``max_abs_error``, ``where``, ``n``, ``n_failed``, ``detail``,
    ``worst``, ``regions``, ``checks``, ``warnings``, ``plot``).

    >>> v = Verdict("sampler pdf", DOES_NOT_CONFORM, "pdf_not_normalised")
    >>> v.id, v.status, v.verdict, v.finding
    ('implementation.sampler_pdf', 'does not conform', 'fail', 'pdf_not_normalised')
    """
    r = Result(quantity=quantity, diagnosis=diagnosis, sentence=sentence, **fields)
    return _as_verdict(r, status, sentence)


def _as_verdict(q: Result, tier: str, sentence: str, **changes: Any) -> Result:
    """``q`` as a verdict of the first screen: kind "quantity", id ``implementation.<quantity>``,
    its tier and sentence (the diagnosis kept only where it does not conform or warns), its
    sub-checks' ids prefixed alike, its regions as [[region, text]] rows."""
    return dataclasses.replace(
        q,
        id="implementation." + q.quantity.replace(" ", "_"),
        kind="quantity",
        outcome="",
        tier=tier,
        sentence=sentence,
        diagnosis=None if tier == CONFORMS else q.diagnosis,
        regions=_regions_rows(q.regions),
        checks=[_implementation_check(c) for c in q.checks],
        **changes,
    )


def _implementation_check(c: Result | dict) -> Result:
    """A sub-check of an implementation's quantity, its id prefixed with ``implementation.``."""
    if isinstance(c, dict):
        c = sub_check(c["id"], c.get("status", ""), c.get("measured"), c.get("threshold"), c.get("detail", ""))
    if not c.id.startswith("implementation."):
        c = dataclasses.replace(c, id="implementation." + c.id)
    return c


def _verdict_dict(v: Result) -> dict[str, Any]:
    return {**v.to_dict(), "label": _QUANTITY_LABEL.get(v.quantity, v.quantity)}


@dataclass
class UnderTest:
    """The implementation under test and its verdicts."""

    name: str
    kind: str
    verdicts: list = field(default_factory=list)
    version: dict = field(default_factory=dict)
    error: str | None = None
    notes: list = field(default_factory=list)

    @property
    def status(self) -> str:
        """The tier: "could not run" if nothing ran, "does not conform" if any graded quantity
        fails, else "conforms with warnings" if any has warnings, else "conforms"."""
        ran = [v for v in self.verdicts if v.status != COULD_NOT_RUN]
        if self.error or not ran:
            return COULD_NOT_RUN
        if any(v.status == DOES_NOT_CONFORM for v in ran):
            return DOES_NOT_CONFORM
        return CONFORMS_WITH_WARNINGS if any(v.status == CONFORMS_WITH_WARNINGS for v in ran) else CONFORMS

    @property
    def verdict_line(self) -> str:
        """The implementation's verdict in one line, the last line of ``report``'s output:
        the tier in capitals, the name and, per quantity that is not a plain pass, its diagnosis.

        >>> ut = UnderTest("mine.glsl", "code", [Verdict("brdf", DOES_NOT_CONFORM, "roughness_squared"),
        ...                                      Verdict("albedo", CONFORMS)])
        >>> ut.verdict_line
        'DOES NOT CONFORM: mine.glsl (brdf: roughness_squared)'
        >>> UnderTest("ref", "code", [Verdict("brdf", CONFORMS), Verdict("properties", CONFORMS)]).verdict_line
        'CONFORMS: ref (BRDF, properties)'
        """
        s = self.status
        if s == COULD_NOT_RUN:
            why = self.error or "; ".join(v.detail for v in self.verdicts if v.detail) or "nothing to grade"
            return f"COULD NOT RUN: {self.name} ({why})"
        if s == CONFORMS:
            labels = [_QUANTITY_LABEL.get(v.quantity, v.quantity) for v in self.verdicts if v.status == CONFORMS]
            return f"CONFORMS: {self.name} ({', '.join(labels)})"
        parts = [
            f"{v.quantity}: {v.diagnosis or (NO_KNOWN if v.status == DOES_NOT_CONFORM else 'warning')}"
            for v in self.verdicts
            if v.status in (DOES_NOT_CONFORM, CONFORMS_WITH_WARNINGS)
        ]
        return f"{s.upper()}: {self.name} ({'; '.join(parts)})"

    @property
    def headline(self) -> str:
        """The first line: the verdict and, when it fails, the first failing quantity's diagnosis."""
        s = self.status
        if s == DOES_NOT_CONFORM:
            v = next(v for v in self.verdicts if v.status == DOES_NOT_CONFORM)
            return f"{self.name} does not conform: {v.sentence}"
        if s == COULD_NOT_RUN:
            why = self.error or "; ".join(v.detail for v in self.verdicts if v.detail) or "nothing to grade"
            return f"{self.name} could not run: {why}"
        if s == CONFORMS_WITH_WARNINGS:
            v = next(v for v in self.verdicts if v.status == CONFORMS_WITH_WARNINGS)
            return f"{self.name} conforms with warnings: {v.sentence}"
        return (
            f"{self.name} conforms ("
            + ", ".join(_QUANTITY_LABEL.get(v.quantity, v.quantity) for v in self.verdicts if v.status == CONFORMS)
            + ")"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "kind": self.kind,
            "status": self.status,
            "tier": self.status,
            "headline": self.headline,
            "verdict_line": self.verdict_line,
            "error": self.error,
            "version": {k: str(v) for k, v in self.version.items()},
            "notes": list(self.notes),
            "verdicts": [_verdict_dict(v) for v in self.verdicts],
        }


def _regions_rows(regions: Any) -> list | None:
    """The grade's breakdown by region (grazing, L.V < 0, roughness bins, dark rho) as
    [[region, text]] rows for the page, whatever mapping / list form the grader gives."""
    if not regions:
        return None
    items = (
        regions.items()
        if isinstance(regions, dict)
        else ((r.get("region", r.get("name", "?")), r) if isinstance(r, dict) else (str(r), "") for r in regions)
    )
    rows = []
    for name, val in items:
        if isinstance(val, dict):
            val = ", ".join(
                f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                for k, v in val.items()
                if k not in ("region", "name")
            )
        rows.append([str(name), str(val)])
    return rows


def _deviation_sentence(name: str | None) -> str:
    if name is None:
        return NO_KNOWN
    try:
        from ..conformance.deviations import DEVIATIONS

        dev = DEVIATIONS[name]
        return f"{name}: {dev.description}"
    except (ImportError, KeyError):
        return str(name)


def _fmt_vec(v: Any) -> str:
    return "—" if v is None else "(" + ", ".join(f"{x:.4g}" for x in v) + ")"


def _where(row: dict | None) -> str:
    """The inputs of a worst row, in words."""
    if not row:
        return ""
    parts = []
    if row.get("wi") is not None:
        wi, wo = row["wi"], row["wo"]
        ldotv = sum(a * b for a, b in zip(wi, wo))
        parts.append(f"wi {_fmt_vec(wi)}, wo {_fmt_vec(wo)} (mu_i {wi[2]:.3g}, mu_o {wo[2]:.3g}, L.V {ldotv:.3g})")
    if row.get("mu") is not None:
        parts.append(f"mu {row['mu']:.3g}")
    if row.get("roughness") is not None:
        parts.append(f"roughness {row['roughness']:.3g}")
    if row.get("rho") is not None:
        parts.append(f"rho {_fmt_vec(row['rho'])}")
    parts.append(f"expected {_fmt_vec(row.get('expected'))}, got {_fmt_vec(row.get('got'))}")
    return f"row {row.get('id', '?')}: " + ", ".join(parts)


def _finite(x: Any) -> float | None:
    try:
        x = float(x)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else (math.inf if x > 0 else None)


def verdict_from_grade(quantity: str, g: dict) -> Result:
    """A quantity's verdict (:func:`Verdict`) from ``Grade.to_dict()`` (or a graded quantity's ``grade``).

    Examples
    --------
    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> from openpbr_diffuse.conformance.deviations import DEVIATIONS
    >>> from openpbr_diffuse.conformance.grade import grade
    >>> v = default_vectors()
    >>> v = v.subset((v.model == "eon") & (v.kind == "brdf"))
    >>> verdict = verdict_from_grade("brdf", grade(v, DEVIATIONS["white_tint"](v)).to_dict())
    >>> verdict.status, verdict.diagnosis, verdict.id
    ('does not conform', 'white_tint', 'implementation.brdf')
    >>> ut = UnderTest("mine", "vectors", [verdict])
    >>> ut.headline.startswith("mine does not conform: white_tint")
    True
    """
    worst = list(g.get("worst") or [])
    passed = bool(g.get("passed"))
    warned = not passed and g.get("tier") == CONFORMS_WITH_WARNINGS
    diag = None if passed else g.get("diagnosis")
    max_abs = g.get("max_abs_error")
    max_abs = math.inf if max_abs == "inf" else _finite(max_abs)
    extra = []
    for key, label in (("n_nan", "NaN"), ("n_inf", "Inf"), ("n_skipped", "skipped")):
        if g.get(key):
            extra.append(f"{g[key]} {label}")
    detail = f"{g.get('n_failed_rows', 0)} of {g.get('n_rows', 0)} rows outside the tolerance"
    if extra:
        detail += " (" + ", ".join(extra) + ")"
    if warned:
        sentence = "conforms with warnings: " + ("; ".join(g.get("warnings") or []) or _deviation_sentence(diag))
    else:
        sentence = "every value within the tolerance" if passed else _deviation_sentence(diag)
    return Verdict(
        quantity,
        CONFORMS_WITH_WARNINGS if warned else (CONFORMS if passed else DOES_NOT_CONFORM),
        diag,
        sentence,
        measured=g.get("max_normalised_error"),
        threshold=1.0,
        unit="x tolerance",
        max_abs_error=max_abs,
        where=_where(worst[0] if worst else None),
        n=int(g.get("n_rows", 0) or 0),
        n_failed=int(g.get("n_failed_rows", 0) or 0),
        detail=detail,
        worst=worst[:10],
        regions=g.get("regions"),
        warnings=list(g.get("warnings") or []) if warned else [],
    )


def verdict_from_quantity(q: Result) -> Result:
    """A quantity's verdict (:func:`Verdict`) from a graded quantity (``graders.grading``),
    its measured value, threshold and sub-checks kept.

    The sampler's quantities carry their own one-sentence diagnosis (``q.sentence``, e.g. "pdf
    integrates to 0.9 at grazing mu_o 0.05, roughness 0.5"), sub-checks and per-case breakdown.
    """
    if q.grade:
        return verdict_from_grade(q.quantity, q.grade)
    passed = bool(q.passed)
    max_abs = _finite(q.max_abs_error)
    if q.sentence is not None:
        failed = [c for c in q.checks if c.get("status") == "fail"]
        warned = passed and any(c.get("status") == "warn" for c in q.checks)
        tier = CONFORMS_WITH_WARNINGS if warned else (CONFORMS if passed else DOES_NOT_CONFORM)
        return _as_verdict(q, tier, q.sentence, max_abs_error=max_abs, n=len(q.checks), n_failed=len(failed))
    if passed:
        sentence = q.detail
    elif q.diagnosis in _known():
        sentence = _deviation_sentence(q.diagnosis)
    else:
        sentence = (q.diagnosis or NO_KNOWN).replace("_", " ") + f" ({q.detail})"
    tier = CONFORMS if passed else DOES_NOT_CONFORM
    return _as_verdict(q, tier, sentence, max_abs_error=max_abs, where=q.detail, n_failed=0 if passed else 1)


def _known() -> set:
    from ..conformance.deviations import DEVIATIONS

    return set(DEVIATIONS)


def grade_vectors_file(path: str | Path) -> UnderTest:
    """Grade a filled vectors file (CSV / JSON) per kind, as ``check FILE`` does."""
    from ..conformance.grade import grade
    from ..conformance.vectors import read_results

    vectors, out = read_results(path)  # ValueError / OSError: unusable input
    ut = UnderTest(name=str(path), kind="vectors")
    out = np.asarray(out, float)
    for kind in ("brdf", "albedo"):
        sel = vectors.kind == kind
        if not sel.any():
            continue
        g = grade(vectors.subset(sel), out[sel])
        ut.verdicts.append(verdict_from_grade(kind, g.to_dict()))
    return ut


def grade_subject_under_test(subject: Subject, *, quick: bool = True, sampler_model: str | None = None) -> UnderTest:
    """Grade a :class:`~openpbr_diffuse.graders.subject.Subject`; missing pieces become "could not run".

    ``sampler_model``: the reference strategy its sampler claims (``graders.grading.grade_sampler``).
    """
    from ..graders.errors import GraderUnavailable
    from ..graders.grading import grade_subject

    ut = UnderTest(name=subject.name, kind="code", version=dict(subject.version), notes=list(subject.notes))
    try:
        result = grade_subject(
            subject, quick=quick, quantities=("brdf", "albedo", "properties", "sampler"), sampler_model=sampler_model
        )
    except GraderUnavailable as exc:
        ut.error = " ".join(str(exc).split())
        return ut
    ut.verdicts = [verdict_from_quantity(q) for q in result.quantities]
    ut.notes += ["sampler: warning: " + "; ".join(v.warnings) for v in ut.verdicts if v.warnings]
    if any(n.startswith("sampler: not graded") for n in ut.notes):
        ut.verdicts.append(Verdict("sampler chi2", COULD_NOT_RUN, detail="the graders here do not run samplers"))
    elif subject.sample is None and subject.pdf is None:
        ut.notes.append("sampler: not graded (give --sample-function and --pdf-function)")
    return ut


# ---------------------------------------------------------------------------------------------
# pictures

_MAP_ROUGHNESS = (0.25, 0.5, 1.0)
_MAP_N = 20
_SLICE_MU_O = (0.2, 0.5, 0.9)


def _grid(n):
    mu = np.linspace(0.02, 0.98, n)
    mi, mo = np.meshgrid(mu, mu, indexing="ij")
    return mu, mi.ravel(), mo.ravel()


def _dirs(mu, phi):
    s = np.sqrt(np.clip(1 - mu * mu, 0, None))
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1)


def _brdf_batch(brdf: Callable[..., Any], mi: np.ndarray, mo: np.ndarray, th: np.ndarray, rho: np.ndarray) -> dict:
    """The subject's first channel on every input the pictures draw, from ONE call of ``brdf``
    (a GLSL or C++ subject pays a process and a GL context per call): keys ("map", dphi, r)
    over the (mu_i, mu_o) grid and ("slice", mu_o, r) over the in-plane theta_i."""
    keys, wis, wos, rs = [], [], [], []
    for dphi in (0.0, math.pi):
        for r in _MAP_ROUGHNESS:
            keys.append((("map", dphi, r), mi.size))
            wis.append(_dirs(mi, 0.0))
            wos.append(_dirs(mo, dphi))
            rs.append(np.full(mi.size, r))
    t = np.radians(th)
    wi_slice = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    for mu_o in _SLICE_MU_O:
        for r in (0.5, 1.0):
            keys.append((("slice", mu_o, r), th.size))
            wis.append(wi_slice)
            wos.append(np.broadcast_to(_dirs(np.array(mu_o), 0.0), (th.size, 3)))
            rs.append(np.full(th.size, r))
    rr = np.concatenate(rs)
    got = np.asarray(brdf(np.concatenate(wis), np.concatenate(wos), rr, np.broadcast_to(rho, (rr.size, 3))), float)
    out, start = {}, 0
    for key, size in keys:
        out[key] = got[start : start + size, 0]
        start += size
    return out


def figures(subject: Subject, ut: UnderTest, image_dir: Path, *, quick: bool = True) -> list:
    """Write the pictures of the subject's values beside the reference's; [(file, caption)]."""
    from ..models import directional_albedo, evaluate
    from ._plot import pyplot

    plt = pyplot()
    model = getattr(subject, "model", "eon") or "eon"
    out = []
    rho = np.array([0.8, 0.8, 0.8])
    if subject.brdf is not None:
        n = 14 if quick else _MAP_N
        mu, mi, mo = _grid(n)
        th = np.linspace(-89.0, 89.0, 90 if quick else 179)
        got_of = _brdf_batch(subject.brdf, mi, mo, th, rho)
        fig, axes = plt.subplots(2, len(_MAP_ROUGHNESS), figsize=(3.2 * len(_MAP_ROUGHNESS), 5.6), squeeze=False)
        for row, (dphi, _label) in enumerate(
            ((0.0, "azimuths equal (L.V >= 0)"), (math.pi, "azimuths opposite (L.V < 0 where mu_i mu_o < sin sin)"))
        ):
            for col, r in enumerate(_MAP_ROUGHNESS):
                wi, wo = _dirs(mi, 0.0), _dirs(mo, dphi)
                rr = np.full(mi.shape, r)
                rh = np.broadcast_to(rho, (mi.size, 3))
                got = got_of[("map", dphi, r)]
                ref = evaluate(model, wi, wo, rr, rh)[:, 0]
                with np.errstate(invalid="ignore", divide="ignore"):
                    err = np.abs(got - ref) / np.maximum(np.abs(ref), 1e-6)
                ax = axes[row, col]
                im = ax.imshow(
                    np.log10(np.maximum(err, 1e-8)).reshape(n, n).T,
                    origin="lower",
                    extent=(mu[0], mu[-1], mu[0], mu[-1]),
                    vmin=-8,
                    vmax=0,
                    cmap="magma",
                )
                ax.set_title(f"r = {r:g}, {'dphi = 0' if row == 0 else 'dphi = pi'}", fontsize=8)
                ax.set_xlabel("mu_i", fontsize=8)
                ax.set_ylabel("mu_o", fontsize=8)
                ax.tick_params(labelsize=7)
        fig.colorbar(im, ax=axes, shrink=0.7, label="log10 relative error")
        out.append(
            (
                "subject_error_maps.png",
                fig,
                (
                    f"log10 of |theirs - reference| / reference over (mu_i, mu_o), rho = 0.8, at roughness "
                    f"{', '.join(map(str, _MAP_ROUGHNESS))}; top: equal azimuths (L.V >= 0), bottom: opposite "
                    "azimuths (L.V < 0 where mu_i mu_o < sin theta_i sin theta_o)"
                ),
            )
        )
        # in-plane lobe slices
        fig, axes = plt.subplots(1, len(_SLICE_MU_O), figsize=(3.4 * len(_SLICE_MU_O), 3.0), squeeze=False)
        for col, mu_o in enumerate(_SLICE_MU_O):
            ax = axes[0, col]
            wo = np.broadcast_to(_dirs(np.array(mu_o), 0.0), (th.size, 3))
            t = np.radians(th)
            wi = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
            for r, c in zip((0.5, 1.0), ("C0", "C3")):
                rr = np.full(th.size, r)
                rh = np.broadcast_to(rho, (th.size, 3))
                ref = evaluate(model, wi, wo, rr, rh)[:, 0] * wi[:, 2]
                got = got_of[("slice", mu_o, r)] * wi[:, 2]
                ax.plot(th, ref, color=c, lw=3, alpha=0.35, label=f"reference r={r:g}")
                ax.plot(th, got, color=c, lw=1, ls="--", label=f"theirs r={r:g}")
            ax.set_title(f"in-plane, mu_o = {mu_o:g}", fontsize=8)
            ax.set_xlabel("theta_i (deg; > 0 on the viewer's side)", fontsize=8)
            ax.tick_params(labelsize=7)
        axes[0, 0].set_ylabel("f cos theta_i (1/sr)", fontsize=8)
        axes[0, 0].legend(fontsize=6)
        fig.tight_layout()
        out.append(
            (
                "subject_lobe_slices.png",
                fig,
                "In-plane slices of f cos theta_i: theirs (dashed) drawn over the reference (wide, pale), rho = 0.8",
            )
        )
    if subject.albedo is not None:
        mu = np.linspace(0.01, 1.0, 60)
        fig, ax = plt.subplots(figsize=(4.5, 3.2))
        for r, c in zip((0.25, 0.5, 1.0), ("C0", "C1", "C3")):
            rr = np.full(mu.size, r)
            rh = np.broadcast_to(np.array([0.5, 0.5, 0.5]), (mu.size, 3))
            ax.plot(
                mu, directional_albedo(model, mu, rr, rh)[:, 0], color=c, lw=3, alpha=0.35, label=f"reference r={r:g}"
            )
            ax.plot(
                mu, np.asarray(subject.albedo(mu, rr, rh), float)[:, 0], color=c, lw=1, ls="--", label=f"theirs r={r:g}"
            )
        ax.set_xlabel("mu = cos theta_o (unitless)")
        ax.set_ylabel("E(mu) (unitless), rho = 0.5")
        ax.legend(fontsize=6)
        fig.tight_layout()
        out.append(("subject_albedo.png", fig, "Directional albedo: theirs (dashed) against the reference (pale)"))
    sampler = next((v for v in ut.verdicts if v.quantity == "sampler chi2" and v.plot), None)
    if sampler is not None:
        out += _sampler_figures(plt, sampler.plot)
    written = []
    for name, fig, caption in out:
        fig.savefig(image_dir / name, dpi=80)
        plt.close(fig)
        written.append((name, caption))
    return written


def _sampler_figures(plt: Any, plot: dict) -> list:
    """The sampler's histograms against its pdf, from the counts the grading computed
    (``graders.grading.grade_sampler``'s ``plot``): marginals over cos theta_i and phi_i per
    case, and the worst case's (observed - expected) / sqrt(expected) over the 2-D bins."""
    cases = plot["cases"]
    z, ph = plot["z_edges"], plot["phi_edges"]
    out = []
    for axis, edges, label, name in ((1, z, "cos theta_i", "cos"), (0, ph, "phi_i (rad)", "phi")):
        fig, axes = plt.subplots(2, (len(cases) + 1) // 2, figsize=(3.2 * ((len(cases) + 1) // 2), 5.4), squeeze=False)
        for ax, c in zip(axes.T.ravel(), cases):
            obs, exp = c["observed"].sum(axis=axis), c["expected"].sum(axis=axis)
            mids = 0.5 * (edges[1:] + edges[:-1])
            ax.bar(mids, obs, width=np.diff(edges), alpha=0.5, label="their samples")
            ax.plot(mids, exp, "k.-", ms=3, lw=1, label="n x their pdf's integral")
            ax.set_title(f"mu_o {c['mu_o']:g}, r {c['roughness']:g}: chi2 p = {c['p']:.2g}", fontsize=8)
            ax.set_xlabel(label, fontsize=8)
            ax.tick_params(labelsize=7)
        axes[0, 0].set_ylabel("samples per bin", fontsize=8)
        axes[0, 0].legend(fontsize=6)
        fig.tight_layout()
        out.append(
            (
                f"subject_sampler_{name}.png",
                fig,
                (
                    f"Their sampler: sample counts over {label} (bars) against the counts their pdf expects "
                    "(dots: n times its integral over each bin, Gauss-Legendre), per (mu_o, roughness) case"
                ),
            )
        )
    worst = min(cases, key=lambda c: c["p"])
    with np.errstate(invalid="ignore", divide="ignore"):
        res = (worst["observed"] - worst["expected"]) / np.sqrt(np.maximum(worst["expected"], 1e-12))
    fig, ax = plt.subplots(figsize=(5.0, 3.2))
    im = ax.imshow(
        np.clip(res, -6, 6),
        origin="lower",
        aspect="auto",
        cmap="coolwarm",
        vmin=-6,
        vmax=6,
        extent=(ph[0], ph[-1], z[0], z[-1]),
    )
    fig.colorbar(im, ax=ax, label="(observed - expected) / sqrt(expected)")
    ax.set_xlabel("phi_i (rad)")
    ax.set_ylabel("cos theta_i")
    ax.set_title(f"worst case mu_o {worst['mu_o']:g}, r {worst['roughness']:g} (p = {worst['p']:.2g})", fontsize=8)
    fig.tight_layout()
    out.append(
        (
            "subject_sampler_residuals.png",
            fig,
            "Their sampler's worst case: standardised residuals of the sample counts per (cos theta, phi) bin",
        )
    )
    return out


__all__ = [
    "CONFORMS",
    "CONFORMS_WITH_WARNINGS",
    "COULD_NOT_RUN",
    "DOES_NOT_CONFORM",
    "EXIT_COULD_NOT_RUN",
    "NO_KNOWN",
    "UnderTest",
    "Verdict",
    "figures",
    "grade_subject_under_test",
    "grade_vectors_file",
    "verdict_from_grade",
]
