"""Grading another implementation's results against the reference, with a diagnosis.

``grade(vectors, out)`` compares the submitted (n, 3) values with the library's float64
reference (:func:`.deviations.reference`) at the tolerance

    |out - ref| <= ABS_TOL + REL_TOL |ref|      (every row, every channel)

and, when that fails, fits every known deviation of :data:`.deviations.DEVIATIONS` (each
variant) to the submitted values and names the one that explains them.  NaN/Inf results
(``non_finite_output``, with the inputs of the rows and the finite value expected there) and
non-zero values below the horizon (``nonzero_below_horizon``) are named on their own and the
other rows diagnosed apart ("non_finite_output & roughness_squared"); when no single
deviation explains the rest, pairs are tried ("constant_factor & roughness_squared"), then
small random-signed relative errors are called ``precision``.  The albedo at exactly mu = 0
is accepted as 0 or as its grazing limit (:func:`accepted_reference`).

Why this tolerance (:data:`TOLERANCE_REASON`): an implementation that is right but works in
float32 differs from the float64 reference by the rounding of its inputs and output and
by float32 arithmetic.  Rounding the default vectors' inputs to float32, evaluating, and
rounding the result to float32 moves the values by at most 6.4e-6 relative (measured, the
largest at the grazing rows, mu = 0.001, where f ~ 1/mu amplifies the input rounding) and
2.4e-5 absolute (on f = 247); a float32 evaluation of the paper's Listing 1 (cancellation in
1 - S^3 of E_F at mu = 0.001) adds ~2e-6 absolute.  REL_TOL = 1e-4 leaves a 15x margin over
the rounding; ABS_TOL = 1e-6 covers values near 0 (f = 0 below the horizon; 1e-6 is 8
float32 ulp of 1).  The smallest deviation to catch, the extra rho on f_ms (Cycles),
moves the albedo by 2 % (0.4689 vs 0.4780): 200x the tolerance.

Examples
--------
>>> from openpbr_diffuse.conformance.vectors import default_vectors
>>> from openpbr_diffuse.conformance.deviations import DEVIATIONS, reference
>>> v = default_vectors()
>>> grade(v, reference(v).astype("float32")).passed
True
>>> g = grade(v, DEVIATIONS["rho_ms_extra_rho"](v))
>>> g.passed, g.diagnosis
(False, 'rho_ms_extra_rho')
"""

from __future__ import annotations

import collections
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..result import (  # re-exported: grade.json_safe, grade.OUT_OF_RANGE
    CONFORMS,
    CONFORMS_WITH_WARNINGS,
    DOES_NOT_CONFORM,
    OUT_OF_RANGE,
    Result,
    json_safe,
)
from .tolerance import ABS_TOL, REL_TOL  # re-exported: grade.ABS_TOL, grade.REL_TOL

if TYPE_CHECKING:
    from .vectors import VectorSet

TOLERANCE_REASON = (
    "|out - ref| <= 1e-6 + 1e-4 |ref| per value. Float32 rounding of the vectors' inputs and of "
    "the result moves the reference by at most 6.4e-6 relative / 2.4e-5 absolute on f = 247 "
    "(measured on this vector set); 1e-4 relative leaves a 15x margin for float32 arithmetic, "
    "1e-6 absolute covers values near 0. The smallest known deviation (extra rho on f_ms) is 2 %."
)
#: A deviation is diagnosed when it matches (within the tolerance) at least this fraction
#: of the values that fail against the reference, and of all graded values.
EXPLAIN_FRACTION = 0.9
#: The diagnosis when no known deviation explains a failure (exactly this sentence).
NOT_EXPLAINED = "no known deviation explains this"
#: How many of the worst rows are listed.
N_WORST = 10
#: Named deviations that are bounded and legitimate in practice: a grade whose only diagnosis
#: is one of them is "conforms with warnings" (with what it is and its size).
WARNING_DEVIATIONS = {
    "eq14_fit_for_exact": "the Eq. 14 fit of E_F where the exact one is claimed (EON paper Listing 1, "
    "exact = false): a bounded approximation; claim eon_approx to conform outright",
}
#: ``precision="half"``: the declared storage precision whose rounding noise is a warning.
PRECISIONS = ("single", "half")


def ulp_half(x: np.ndarray) -> np.ndarray:
    """One unit in the last place of IEEE float16 at ``|x|`` (2^-24 below the normal range).

    >>> ulp_half(np.array([1.0, 0.3, 1e-6])).tolist()
    [0.0009765625, 0.000244140625, 5.960464477539063e-08]
    """
    a = np.abs(np.asarray(x, np.float64))
    e = np.floor(np.log2(np.maximum(a, 2.0**-14)))
    return np.where(np.isfinite(a), 2.0 ** (e - 10), np.inf)


@dataclass
class Grade(Result):
    """The result of :func:`grade`: a :class:`~openpbr_diffuse.result.Result` (``measured``:
    the largest error in tolerances, ``threshold`` 1, its tier, ``finding`` the named deviation,
    ``worst`` the worst rows) with the diagnosis's details (see the module docstring;
    ``to_dict()`` for JSON).  ``passed``: every value within the tolerance."""

    kind: str = "quantity"
    diagnosis_detail: str = ""
    candidates: dict = field(default_factory=dict)
    candidate_details: dict = field(default_factory=dict)
    n_rows: int = 0
    n_failed_rows: int = 0
    max_rel_error: float = 0.0
    max_normalised_error: float = 0.0
    models: list = field(default_factory=list)
    version: str = ""
    n_nan: int = 0
    n_inf: int = 0
    n_skipped: int = 0
    candidate_match_fractions: dict = field(default_factory=dict)
    #: which EON term the failing values get wrong (:func:`.terms.which_term`), or None
    terms: str | None = None
    #: the properties the rows show (:func:`.properties.vector_properties`): checks with ids
    properties: list = field(default_factory=list)
    #: when nothing is named: the deviation that comes closest (:func:`_closest`), with its
    #: residual beyond the tolerance -- None when none reduces the error enough
    closest: dict | None = None

    def to_dict(self) -> dict[str, Any]:
        extra = {"closest": self.closest} if self.closest else {}
        return json_safe(
            {
                **Result.to_dict(self),
                **extra,
                "passed": self.passed,
                "version": self.version,
                "models": self.models,
                "n_rows": self.n_rows,
                "n_failed_rows": self.n_failed_rows,
                "max_abs_error": self.max_abs_error,
                "max_rel_error": self.max_rel_error,
                "rms_error": self.rms_error,
                "max_normalised_error": self.max_normalised_error,
                "tolerance": self.tolerance,
                "tolerance_reason": self.tolerance_reason,
                "worst": self.worst,
                "diagnosis": self.diagnosis,
                "diagnosis_detail": self.diagnosis_detail,
                "candidates": self.candidates,
                "candidate_details": self.candidate_details,
                "regions": self.regions,
                "n_nan": self.n_nan,
                "n_inf": self.n_inf,
                "n_skipped": self.n_skipped,
                "candidate_match_fractions": self.candidate_match_fractions,
                "terms": self.terms,
                "tier": self.tier,
                "warnings": self.warnings,
                "properties": self.properties,
            }
        )


def accepted_reference(vectors: VectorSet, out: np.ndarray, absolute: float = ABS_TOL) -> np.ndarray:
    """The reference of every row (:func:`.deviations.reference`), with the single-sided
    convention accepted where the albedo is asked for at exactly mu = 0: a row whose submitted
    values are all 0 (within ``absolute``) is compared with 0, any other with the grazing
    limit the library returns (E -> rho for EON/FON, since E_F -> 1).

    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> v = default_vectors()
    >>> v = v.subset((v.kind == "albedo") & (v.mu == 0) & (v.model == "eon"))
    >>> float(accepted_reference(v, np.zeros((len(v), 3))).max()), round(float(accepted_reference(v, np.ones((len(v), 3))).max()), 6)
    (0.0, 1.0)
    """
    from .deviations import reference

    ref = reference(vectors)
    out = np.asarray(out, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        zero = (vectors.kind == "albedo") & (vectors.mu == 0) & (np.abs(out) <= absolute).all(axis=1)
    ref[zero] = 0.0
    return ref


def _tolerance(tolerance):
    if tolerance is None:
        return REL_TOL, ABS_TOL
    if isinstance(tolerance, (tuple, list)) and len(tolerance) == 2:
        rel, ab = (float(t) for t in tolerance)
    elif isinstance(tolerance, (int, float)) and not isinstance(tolerance, bool):
        rel, ab = float(tolerance), ABS_TOL
    else:
        raise TypeError("tolerance must be None, a relative tolerance (float) or (relative, absolute)")
    if not (math.isfinite(rel) and math.isfinite(ab) and rel >= 0 and ab >= 0 and rel + ab > 0):
        raise ValueError(f"tolerance must be finite, >= 0 and not both 0; got relative {rel}, absolute {ab}")
    return rel, ab


def _normalised(out, pred, rel, ab):
    """|out - pred| / tolerance: inf where out or pred is NaN/Inf, :data:`OUT_OF_RANGE`
    where both are finite but the ratio overflows."""
    with np.errstate(all="ignore"):
        e = np.abs(out - pred) / (ab + rel * np.abs(pred))
        both = np.isfinite(out) & np.isfinite(pred)
    return np.where(np.isfinite(e), e, np.where(both, OUT_OF_RANGE, np.inf))


def _row(vectors, i, ref, out, e):
    def vec(a):
        return None if np.isnan(a).all() else [float(x) for x in a]

    def num(x):
        return None if math.isnan(float(x)) else float(x)

    brdf = str(vectors.kind[i]) == "brdf"
    got = out[i]
    if np.isnan(got).any():
        status = "nan"
    elif np.isinf(got).any():
        status = "inf"
    else:
        status = "fail" if e[i].max() > 1.0 else "ok"
    return {
        "id": str(vectors.id[i]),
        "kind": str(vectors.kind[i]),
        "model": str(vectors.model[i]),
        "wi": vec(vectors.wi[i]),
        "wo": vec(vectors.wo[i]),
        "mu": num(vectors.mu[i]),
        "mu_i": float(vectors.wi[i, 2]) if brdf else None,
        "mu_o": float(vectors.wo[i, 2]) if brdf else num(vectors.mu[i]),
        "ldotv": float(vectors.wi[i] @ vectors.wo[i]) if brdf else None,
        "roughness": num(vectors.roughness[i]),
        "rho": vec(vectors.rho[i]),
        "expected": [float(x) for x in ref[i]],
        "got": [float(x) for x in got],
        "status": status,
        "abs_error": float(np.max(np.abs(got - ref[i]))) if np.isfinite(got).all() else math.inf,
        "normalised_error": float(e[i].max()),
    }


#: Roughness bins of the region breakdown (the value as given: r, or sigma in radians).
ROUGHNESS_BINS = ((0.0, 0.0), (0.0, 0.25), (0.25, 0.5), (0.5, 1.0), (1.0, math.inf))


def region_masks(vectors: VectorSet) -> dict[str, np.ndarray]:
    """{region name: (n,) bool mask} of the breakdown by region.

    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> sorted(region_masks(default_vectors()))[:2]
    ['L.V < 0', 'all']
    """
    brdf = vectors.kind == "brdf"
    with np.errstate(invalid="ignore"):
        mu_min = np.where(brdf, np.minimum(vectors.wi[:, 2], vectors.wo[:, 2]), vectors.mu)
        ldotv = np.einsum("ij,ij->i", vectors.wi, vectors.wo)
        masks = {
            "all": np.ones(len(vectors), bool),
            "grazing (mu < 0.1)": ((mu_min > 0) | ~brdf) & (mu_min < 0.1),
            "L.V < 0": brdf & (ldotv < 0) & (vectors.wi[:, 2] > 0) & (vectors.wo[:, 2] > 0),
            "below the horizon": brdf & ((vectors.wi[:, 2] <= 0) | (vectors.wo[:, 2] <= 0)),
        }
        r = vectors.roughness
        for lo, hi in ROUGHNESS_BINS:
            if lo == hi:
                masks[f"roughness = {lo:g}"] = r == lo
            elif math.isinf(hi):
                masks[f"roughness > {lo:g}"] = r > lo
            else:
                masks[f"roughness in ({lo:g}, {hi:g}]"] = (r > lo) & (r <= hi)
        masks["dark (rho < 0.1)"] = (vectors.rho < 0.1).any(axis=1)
    return masks


def _region_names():
    names = ["all", "grazing (mu < 0.1)", "L.V < 0", "below the horizon"]
    for lo, hi in ROUGHNESS_BINS:
        names.append(
            f"roughness = {lo:g}"
            if lo == hi
            else f"roughness > {lo:g}"
            if math.isinf(hi)
            else f"roughness in ({lo:g}, {hi:g}]"
        )
    return names + ["dark (rho < 0.1)"]


def _regions(vectors, row_e):
    out = []
    for name, m in region_masks(vectors).items():
        n = int(m.sum())
        if n == 0:
            continue
        out.append(
            {
                "region": name,
                "n": n,
                "n_failed": int((row_e[m] > 1.0).sum()),
                "max_normalised_error": float(row_e[m].max()),
            }
        )
    return out


def where_it_fails(regions: list[dict]) -> str:
    """One sentence: the regions with failures, worst first ("" when nothing fails)."""
    bad = sorted((r for r in regions if r["n_failed"] and r["region"] != "all"), key=lambda r: -r["n_failed"] / r["n"])
    parts = [f"{r['region']}: {r['n_failed']}/{r['n']} rows" for r in bad]
    return "fails in " + "; ".join(parts) if parts else ""


def _swapped(vectors):
    """The rows with wi and wo exchanged (an implementation that swapped its arguments)."""
    return type(vectors)(
        vectors.id,
        vectors.kind,
        vectors.model,
        vectors.wo,
        vectors.wi,
        vectors.mu,
        vectors.roughness,
        vectors.rho,
        vectors.version,
    )


def _rows_key(vectors):
    """A digest of the rows' contents (what a deviation's prediction depends on)."""
    import hashlib

    h = hashlib.blake2b(digest_size=16)
    for a in (vectors.wi, vectors.wo, vectors.mu, vectors.roughness, vectors.rho):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    for a in (vectors.kind, vectors.model):
        h.update("\0".join(map(str, a)).encode())
    return h.digest()


#: Predictions of the fixed (unfitted) deviation variants, by (rows digest, predictor, swapped):
#: they depend on the rows only, and a program grading several implementations on the same
#: vectors (the report's known-deviation table, the graders) predicts each once.
_PREDICTIONS: collections.OrderedDict = collections.OrderedDict()
_PREDICTIONS_KEPT = 256


def _prediction(predictor, vectors, key, swapped):
    k = (key, id(predictor), swapped)
    pred = _PREDICTIONS.get(k)
    if pred is None:
        pred = predictor(_swapped(vectors) if swapped else vectors)
        pred.flags.writeable = False
        _PREDICTIONS[k] = pred
        while len(_PREDICTIONS) > _PREDICTIONS_KEPT:
            _PREDICTIONS.popitem(last=False)
    else:
        _PREDICTIONS.move_to_end(k)
    return pred


def _variants(vectors, out, ref, rel, ab):
    """Yield (name, label, prediction) of every deviation variant (fitted ones fitted to
    ``out``; fixed, non-reciprocal ones also with wi and wo swapped).  The fixed variants'
    predictions are read-only arrays, remembered per rows' contents (``_prediction``)."""
    from .deviations import DEVIATIONS, Fitted

    weight = 1.0 / (ab + rel * np.abs(ref))
    key = _rows_key(vectors)
    for name, dev in DEVIATIONS.items():
        for label, predictor in dev.variants:
            if isinstance(predictor, Fitted):
                param, pred = predictor.fit(vectors, out, ref, weight)
                yield name, predictor.label(param), pred
                continue
            pred = _prediction(predictor, vectors, key, False)
            yield name, label, pred
            if not (vectors.kind == "brdf").any():
                continue
            pred_s = _prediction(predictor, vectors, key, True)
            both = np.isfinite(pred) & np.isfinite(pred_s)
            if (_normalised(pred_s, pred, rel, ab)[both] > 1.0).any():
                yield f"{name}+wi_wo_swapped", f"{label}, with wi and wo swapped", pred_s


#: How many rows with a NaN/Inf result are named in the diagnosis.
N_NONFINITE = 3


def _below_horizon(vectors):
    return (vectors.kind == "brdf") & ((vectors.wi[:, 2] <= 0) | (vectors.wo[:, 2] <= 0))


def _fmt(x):
    return "-" if x is None else f"{x:.6g}"


def _inputs(w):
    rho = "(" + ", ".join(f"{x:.6g}" for x in w["rho"]) + ")" if w["rho"] else "-"
    where = (
        f"mu_i {_fmt(w['mu_i'])}, mu_o {_fmt(w['mu_o'])}" if w["kind"] == "brdf" else f"albedo at mu {_fmt(w['mu'])}"
    )
    return f"{w['id']} [{w['model']}] ({where}, roughness {_fmt(w['roughness'])}, rho {rho})"


def _limit_note(w):
    """What the value is at a row where a NaN/Inf was returned, and why it is finite."""
    expected = "(" + ", ".join(f"{x:.6g}" for x in w["expected"]) + ")"
    if w["kind"] == "brdf" and min(w["mu_i"], w["mu_o"]) <= 0.0:
        return (
            f"expected {expected}: a direction with z <= 0 is below the horizon, f = 0 (test z <= 0, not z < 0; "
            "and f stays finite as mu -> 0)"
        )
    if w["kind"] == "albedo" and w["mu"] == 0.0:
        lim = " (E_F -> 1 as mu -> 0, so E -> rho)" if w["model"] in ("eon", "eon_approx", "fon") else ""
        return (
            f"expected the limit {expected}{lim} or 0 (single-sided); guard (S/mu)(1 - S^3) of Eq. 13, "
            "e.g. as S mu (1 + S + S^2)/(1 + S)"
        )
    if w["kind"] == "brdf" and min(w["mu_i"], w["mu_o"]) >= 1.0:
        return f"expected {expected} (along the normal: s = 0, sin(theta) = 0)"
    return f"expected {expected}"


def _nonfinite_text(rows, n_rows, n_nan, n_inf):
    what = " and ".join(f"{n} {w}" for n, w in ((n_nan, "NaN"), (n_inf, "Inf")) if n)
    shown = "; ".join(f"{_inputs(w)}: {_limit_note(w)}" for w in rows)
    return f"NaN/Inf output ({what} values in {n_rows} rows), e.g. {shown}"


def _below_text(vectors, out):
    from .deviations import DEVIATIONS

    dev = DEVIATIONS["nonzero_below_horizon"]
    k = np.flatnonzero(np.any(out != 0, axis=1))
    i = int(k[0]) if k.size else 0
    first = f"{vectors.id[i]} (wi.z {vectors.wi[i, 2]:.6g}, wo.z {vectors.wo[i, 2]:.6g}) got {out[i].max():.6g}"
    return (
        f"{dev.description} [{dev.source}]: {len(vectors)} rows below the horizon, e.g. {first}; "
        "the rows above the horizon are graded on their own"
    )


#: Precision noise: the median relative error at most ``PRECISION_MEDIAN``, 95 % of them within
#: ``PRECISION_Q95`` (cancellation amplifies the rounding at a few rows), of both signs.
PRECISION_MEDIAN = 5e-3
PRECISION_Q95 = 2e-2


def _precision(vectors, out, ref, rel, ab):
    """ "precision ~ x, not a formula bug" when the failing values are off by small relative
    errors of random sign (e.g. every intermediate rounded to a few digits); else None."""
    with np.errstate(all="ignore"):
        big = np.abs(ref) > 1e3 * ab
        d = (out - ref) / np.where(big, ref, 1.0)
        fail = big & (_normalised(out, ref, rel, ab) > 1.0)
    if fail.sum() < 20 or not np.isfinite(d[big]).all():
        return None
    r = np.abs(d[big])
    med, q95 = float(np.median(r)), float(np.quantile(r, 0.95))
    if med > PRECISION_MEDIAN or q95 > PRECISION_Q95 or r.max() > 10 * PRECISION_Q95:
        return None
    pos = float((d[fail] > 0).mean())
    if not 0.2 <= pos <= 0.8:
        return None  # one-signed: a bias, not noise
    # noise has no place: failing values gathered in one region (e.g. every one at rho < 0.1,
    # as a clamp of dark albedos gives) are a formula's structure, not precision
    fail_rows = fail.reshape(len(vectors), -1).any(axis=1)
    for name, mask in region_masks(vectors).items():
        if name != "all" and 10 <= mask.sum() and mask.mean() <= 0.5 and fail_rows[mask].sum() >= 0.9 * fail_rows.sum():
            return None
    return (
        f"precision ~ {med:.1g} (median relative error; 95 % within {q95:.1g}, {pos:.0%} of the failing "
        "values too large, the rest too small), not a formula bug: no known deviation explains it; keep "
        "more digits in the intermediates (float32 throughout is within the tolerance)"
    )


def _indistinguishable(name, label, singles, ref, rel, ab):
    """Other named deviations whose predictions equal the chosen one's on every row both
    predict (e.g. on albedo rows alone white_tint and Lambert-for-EON both give rho)."""
    chosen = next(pred for n, lab, pred in singles if n == name and lab == label)
    twins = []
    for other, _, pred in singles:
        if other == name or other in twins:
            continue
        both = np.isfinite(pred) & np.isfinite(chosen)
        r, a = np.broadcast_to(rel, pred.shape)[both], np.broadcast_to(ab, pred.shape)[both]
        if both.mean() >= 0.5 and (_normalised(pred[both], chosen[both], r, a) <= 0.01).all():
            twins.append(other)
    return twins


def _diagnose(vectors, out, ref, e_ref, rel, ab, singles=None):
    """Fit every deviation variant: (name or None, detail, {name: residual}, {name: details},
    {name: fraction of the failing values it matches}); ``singles`` (a list) receives the
    (name, label, prediction) of every distinguishable variant."""
    from .deviations import DEVIATIONS

    failing = e_ref > 1.0
    n_fail = int(failing.sum())
    candidates, details, fractions = {}, {}, {}
    best = None
    singles = [] if singles is None else singles  # (name, label, prediction): the pairs' factors
    for name, label, pred in _variants(vectors, out, ref, rel, ab):
        known = np.isfinite(pred)  # NaN: the deviation makes no prediction there
        if known.mean() < 0.5 or not (_normalised(pred, ref, rel, ab)[known] > 1.0).any():
            details.setdefault(name, {"distinguishable": False})
            continue  # indistinguishable from the reference on these rows
        e = _normalised(out, pred, rel, ab)
        fk = failing & known
        explained = float((e[fk] <= 1.0).mean()) if fk.any() else 0.0
        overall = float((e[known] <= 1.0).mean())
        residual = float(np.sqrt(np.mean(np.minimum(e[known], 1e6) ** 2)))
        key = (explained, overall, -residual)
        prev = details.get(name)
        if prev is None or not prev.get("distinguishable") or key > prev["_key"]:
            details[name] = {
                "distinguishable": True,
                "variant": label,
                "explained_fraction": explained,
                "matching_fraction": overall,
                "residual": residual,
                "_key": key,
            }
            candidates[name] = residual
            fractions[name] = explained
        if best is None or key > best[0]:
            best = (key, name, label, explained, overall)
        singles.append((name, label, pred))
    for d in details.values():
        d.pop("_key", None)
    if best is not None:
        _, name, label, explained, overall = best
        if explained >= EXPLAIN_FRACTION and overall >= EXPLAIN_FRACTION:
            dev = DEVIATIONS[name.split("+")[0]]
            text = (
                f"{dev.description} [{dev.source}]: {label}; matches {explained:.0%} of the {n_fail} "
                f"failing values and {overall:.0%} of all values within the tolerance"
            )
            twins = _indistinguishable(name, label, singles, ref, rel, ab)
            if twins:
                details[name]["indistinguishable_from"] = twins
                text += f"; these rows cannot tell it from: {', '.join(twins)} (other rows, e.g. the BRDF's, can)"
            return name, text, candidates, details, fractions
    pair = _best_pair(singles, out, ref, failing, rel, ab)
    if pair is not None:
        (n1, l1), (n2, l2), explained, overall = pair
        d1, d2 = DEVIATIONS[n1.split("+")[0]], DEVIATIONS[n2.split("+")[0]]
        text = (
            f"two deviations at once (no single one explains this): (1) {d1.description} [{d1.source}]: {l1}; "
            f"(2) {d2.description} [{d2.source}]: {l2}; together they match {explained:.0%} of the {n_fail} "
            f"failing values and {overall:.0%} of all values within the tolerance"
        )
        return f"{n1} & {n2}", text, candidates, details, fractions
    return None, NOT_EXPLAINED, candidates, details, fractions


#: The closest named deviation (:func:`_closest`) is stated when its RMS normalised error is at
#: most 1/CLOSEST_FACTOR of the reference's, no value (|ref| > 1e3 x absolute) is off it by more
#: than CLOSEST_MAX_REL relative and the RMS relative residual is at most CLOSEST_RMS_REL: a
#: residual of a rasteriser's precision (EEVEE: 2.7 % max, 0.6 % rms around Lambert), not of a
#: second bug (a mu floor's grazing error is tens of percent).
CLOSEST_FACTOR = 5.0
CLOSEST_MAX_REL = 0.05
CLOSEST_RMS_REL = 0.02


def _closest(singles, out, ref, rel, ab):
    """The known deviation (or a constant factor times one) that explains the values best when
    none explains them within the tolerance: a dict (name, variant, description, residuals,
    improvement) or None when none comes within :data:`CLOSEST_FACTOR` and the residual caps."""
    from .deviations import DEVIATIONS, factor_name

    def rms(e):
        e = np.minimum(e[np.isfinite(e)], 1e6)
        return float(np.sqrt(np.mean(e**2))) if e.size else math.inf

    with np.errstate(all="ignore"):
        big = np.abs(ref) > 1e3 * ab
        if big.sum() < 3:
            return None
        ref_rms = rms(_normalised(out, ref, rel, ab))
        w2 = (1.0 / (ab + rel * np.abs(ref))) ** 2
        options = []
        for name, label, pred in singles:
            if np.isfinite(pred).mean() < 0.5:
                continue
            options.append((name, label, pred))
            sel = np.isfinite(pred) & np.isfinite(out)
            den = float(np.sum(np.where(sel, w2 * pred * pred, 0.0)))
            k = float(np.sum(np.where(sel, w2 * out * pred, 0.0)) / den) if den > 0 else 1.0
            if math.isfinite(k) and k > 0 and abs(k - 1.0) > 1e-3 and not name.startswith("constant_factor"):
                options.append((f"constant_factor & {name}", f"{factor_name(k)}; {label}", k * pred))
        best = {}  # "single" / "scaled" -> (residual, name, label, prediction)
        for name, label, pred in options:
            res = rms(_normalised(out, pred, rel, ab))
            kind = "scaled" if " & " in name else "single"
            if kind not in best or res < best[kind][0]:
                best[kind] = (res, name, label, pred)
        if not best:
            return None
        # a constant factor on top only when it halves the residual (not a 0.1 % exposure)
        single, scaled = best.get("single"), best.get("scaled")
        pick = scaled if single is None or (scaled is not None and scaled[0] < 0.5 * single[0]) else single
        res, name, label, pred = pick
        d = np.abs(out - pred)[big] / np.abs(pred[big])
        d_ref = np.abs(out - ref)[big] / np.abs(ref[big])
        if not np.isfinite(d).all():
            return None
        max_rel, rms_rel = float(d.max()), float(np.sqrt(np.mean(d**2)))
    if not (res * CLOSEST_FACTOR <= ref_rms and max_rel <= CLOSEST_MAX_REL and rms_rel <= CLOSEST_RMS_REL):
        return None
    dev = DEVIATIONS[name.split(" & ")[-1].split("+")[0]]
    return {
        "deviation": name,
        "variant": label,
        "description": dev.description,
        "source": dev.source,
        "residual_max_rel": max_rel,
        "residual_rms_rel": rms_rel,
        "reference_max_rel": float(np.max(d_ref)),
        "residual_rms_normalised": res,
        "reference_rms_normalised": ref_rms,
        "improvement": ref_rms / max(res, 1e-300),
        "tolerance_relative": rel,
    }


def closest_text(c: dict) -> str:
    """The sentence of a closest named deviation (see :func:`_closest`).

    >>> closest_text({"deviation": "no_energy_compensation_lambert", "variant": "lambert",
    ...     "description": "Lambert instead of EON", "source": "x", "residual_max_rel": 0.027,
    ...     "residual_rms_rel": 0.0063, "reference_max_rel": 0.87, "improvement": 40.0,
    ...     "tolerance_relative": 0.005})[:80]
    'closest named deviation: no_energy_compensation_lambert (Lambert instead of EON '
    """
    return (
        f"closest named deviation: {c['deviation']} ({c['description']} [{c['source']}]: {c['variant']}): "
        f"residual {100 * c['residual_max_rel']:.2g} % max, {100 * c['residual_rms_rel']:.2g} % rms "
        f"(against the reference {100 * c['reference_max_rel']:.2g} % max; {c['improvement']:.0f}x smaller "
        f"in tolerances), beyond the tolerance ({100 * c['tolerance_relative']:.2g} % relative) -- likely "
        "the implementation's noise/precision on top of that deviation"
    )


def _pair_key(out, pred, known, failing, rel, ab):
    e = _normalised(out, pred, rel, ab)
    fk = failing & known
    explained = float((e[fk] <= 1.0).mean()) if fk.any() else 0.0
    overall = float((e[known] <= 1.0).mean()) if known.any() else 0.0
    return explained, overall


def _best_pair(singles, out, ref, failing, rel, ab):
    """The pair of deviations (of different names) whose composition explains the values:
    a constant factor k times another deviation's prediction (k fitted), or two predictions
    composed multiplicatively (p1 p2 / ref: one scales what the other computes) or additively
    (p1 + p2 - ref: they change different terms).  (label pair, explained, overall) or None."""
    weight2 = (1.0 / (ab + rel * np.abs(ref))) ** 2
    with np.errstate(all="ignore"):
        nz = np.abs(ref) > 0
        usable = [
            (n, lab, p)
            for n, lab, p in singles
            if np.isfinite(p).mean() >= 0.5 and not n.startswith(("constant_factor", "nonzero_below_horizon"))
        ]
        best = None

        def consider(a, b, pred):
            nonlocal best
            known = np.isfinite(pred)
            if known.mean() < 0.5:
                return
            explained, overall = _pair_key(out, pred, known, failing, rel, ab)
            if explained >= EXPLAIN_FRACTION and overall >= EXPLAIN_FRACTION:
                if best is None or (explained, overall) > best[2:]:
                    best = (a, b, explained, overall)

        from .deviations import factor_name

        for n, lab, p in usable:  # k x p
            sel = np.isfinite(p) & np.isfinite(out)
            den = float(np.sum(np.where(sel, weight2 * p * p, 0.0)))
            if den <= 0:
                continue
            k = float(np.sum(np.where(sel, weight2 * out * p, 0.0)) / den)
            if math.isfinite(k) and abs(k - 1.0) > 1e-3 and k != 0:
                consider(("constant_factor", factor_name(k)), (n, lab), k * p)
        for i, (n1, l1, p1) in enumerate(usable):
            for n2, l2, p2 in usable[i + 1 :]:
                if n1.split("+")[0] == n2.split("+")[0]:
                    continue
                consider((n1, l1), (n2, l2), np.where(nz, p1 * p2 / np.where(nz, ref, 1.0), p1 + p2 - ref))
                consider((n1, l1), (n2, l2), p1 + p2 - ref)
    return best


def grade(
    vectors: VectorSet,
    out: np.ndarray,
    *,
    model: str | None = None,
    tolerance: float | tuple | None = None,
    n_skipped: int = 0,
    precision: str | None = None,
) -> Grade:
    """Grade submitted values ``out`` (n, 3) for the rows of ``vectors``.

    Parameters
    ----------
    vectors : VectorSet
        The rows the values answer (e.g. from :func:`.vectors.read_results`).
    out : array_like, shape (n, 3)
        The implementation's BRDF values (no cosine) / directional albedos.
    model : str, optional
        Grade only the rows of this model (a name of :data:`.vectors.VECTOR_MODELS`).
    tolerance : None, float or (float, float)
        None: the stated default (``REL_TOL``, ``ABS_TOL``); a float: relative tolerance
        (absolute stays ``ABS_TOL``); a pair: (relative, absolute).
    n_skipped : int
        Rows of the file left blank (not graded; reported as ``n_skipped``).
    precision : {None, "single", "half"}
        The precision the implementation declares: with ``"half"`` values off by at most one
        float16 ulp beyond the tolerance give the tier "conforms with warnings".

    Returns
    -------
    Grade
        ``passed`` when every value is within the tolerance; ``diagnosis`` names the known
        deviation that explains a failure (None when it conforms or nothing explains it:
        ``diagnosis_detail`` then starts with :data:`NOT_EXPLAINED`); ``regions`` is the
        breakdown by region, ``n_nan`` / ``n_inf`` count non-finite values.
    """

    rel, ab = _tolerance(tolerance)
    try:
        out = np.asarray(out, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError("out must be an (n, 3) array of numbers") from None
    if out.shape != (len(vectors), 3):
        raise ValueError(f"out must have shape ({len(vectors)}, 3) (one RGB value per vector), got {out.shape}")
    if model is not None:
        keep = vectors.model == model
        if not keep.any():
            raise ValueError(f"model: no rows of model {model!r} (rows have {', '.join(sorted(set(vectors.model)))})")
        vectors, out = vectors.subset(keep), out[keep]
    if len(vectors) == 0:
        raise ValueError("vectors: nothing to grade (0 rows)")
    acc = _Accumulator(rel, ab, precision)
    acc.add(vectors, out)
    return acc.result(tolerance, n_skipped)


#: The diagnosis fits at most this many rows (a seeded sample chosen by row position when a
#: streamed file has more; every row otherwise).
DIAGNOSIS_ROWS = 50_000


def _row_keys(start, n):
    """A pseudo-random key per global row position (splitmix64): the diagnosis sample is the
    rows with the smallest keys, the same whatever the chunking."""
    x = np.arange(start, start + n, dtype=np.uint64) + np.uint64(0x9E3779B97F4A7C15)
    with np.errstate(over="ignore"):
        x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def _concat(parts):
    from .vectors import VectorSet

    return VectorSet(
        *(
            np.concatenate([getattr(v, f) for v in parts])
            for f in ("id", "kind", "model", "wi", "wo", "mu", "roughness", "rho")
        ),
        version=parts[0].version,
    )


class _Accumulator:
    """Grade chunk by chunk: totals, regions, worst rows and a bounded sample for the diagnosis."""

    def __init__(self, rel, ab, precision=None):
        self.rel, self.ab = rel, ab
        if precision not in (None, *PRECISIONS):
            raise ValueError(f"precision: expected one of {', '.join(PRECISIONS)}, got {precision!r}")
        self.half = precision == "half"
        self.max_norm_half = 0.0  # max |out - ref| / (abs + rel |ref| + ulp_half(ref))
        self.n = self.n_failed = self.n_nan = self.n_inf = self.n_values = 0
        self.max_abs = self.max_rel = self.max_norm = 0.0
        self.sum_sq, self.scale = 0.0, 0.0  # sum of (diff / scale)^2: no overflow at 1e308
        self.finite = True
        self.models, self.version = set(), ""
        self.regions = {}
        self.worst = []  # (-row_e, position, row dict)
        self.sample = None  # (keys, positions, vectors, out)
        self.nonfinite = []  # rows with a NaN/Inf result, one per kind of place (row dicts)
        self.nonfinite_kinds = set()
        self.n_nonfinite_rows = 0

    def add(self, vectors, out):
        # the submitted values may be anything (1e308, inf, nan): every overflow and invalid
        # operation below is expected, and accounted for (OUT_OF_RANGE, n_nan, n_inf)
        with np.errstate(all="ignore"):
            self._add(vectors, out)

    def _add(self, vectors, out):
        if len(vectors) == 0:
            return
        rel, ab = self.rel, self.ab
        ref = accepted_reference(vectors, out, ab)
        e = _normalised(out, ref, rel, ab)
        diff = np.abs(out - ref)
        rel_err = diff / np.maximum(np.abs(ref), 1e-300)
        rel_err = np.where(np.isfinite(rel_err) | ~np.isfinite(diff), rel_err, OUT_OF_RANGE)
        finite = bool(np.isfinite(out).all())
        row_e = e.max(axis=1)
        start = self.n
        self.n += len(vectors)
        self.version = vectors.version
        self.models |= set(map(str, np.unique(vectors.model)))
        self.n_failed += int((row_e > 1.0).sum())
        self.n_nan += int(np.isnan(out).sum())
        self.n_inf += int(np.isinf(out).sum())
        self.finite &= finite
        self.max_norm = max(self.max_norm, float(row_e.max()))
        if self.half:
            e_half = np.nan_to_num(diff / (ab + rel * np.abs(ref) + ulp_half(ref)), nan=np.inf)
            self.max_norm_half = max(self.max_norm_half, float(e_half.max()))
        if self.finite:
            top = float(np.max(diff))
            self.max_abs = max(self.max_abs, top)
            if top > self.scale:
                self.sum_sq *= (self.scale / top) ** 2
                self.scale = top
            if self.scale > 0:
                self.sum_sq += float(np.sum((diff / self.scale) ** 2))
            self.n_values += diff.size
            self.max_rel = max(
                self.max_rel, float(np.max(np.where(np.abs(ref) > 0, rel_err, np.where(diff > 0, math.inf, 0.0))))
            )
        for r in _regions(vectors, row_e):
            t = self.regions.setdefault(
                r["region"], {"region": r["region"], "n": 0, "n_failed": 0, "max_normalised_error": 0.0}
            )
            t["n"] += r["n"]
            t["n_failed"] += r["n_failed"]
            t["max_normalised_error"] = max(t["max_normalised_error"], r["max_normalised_error"])
        order = np.argsort(-row_e, kind="stable")[:N_WORST]
        self.worst += [
            (-float(row_e[i]), start + int(i), _row(vectors, int(i), ref, out, e)) for i in order if row_e[i] > 0
        ]
        self.worst = sorted(self.worst, key=lambda t: (t[0], t[1]))[:N_WORST]
        bad = np.flatnonzero(~np.isfinite(out).all(axis=1))
        self.n_nonfinite_rows += int(bad.size)
        if bad.size and len(self.nonfinite) < N_NONFINITE:
            # one row of each kind of place (BRDF at mu_i = 0, at mu_o = 0, albedo at mu = 0, ...)
            sig = np.stack(
                [
                    vectors.kind[bad] == "brdf",
                    vectors.wi[bad, 2] <= 0,
                    vectors.wo[bad, 2] <= 0,
                    vectors.mu[bad] == 0,
                ],
                axis=1,
            )
            for j in np.unique(sig, axis=0, return_index=True)[1]:
                key = tuple(sig[j])
                if key not in self.nonfinite_kinds and len(self.nonfinite) < N_NONFINITE:
                    self.nonfinite_kinds.add(key)
                    self.nonfinite.append(_row(vectors, int(bad[j]), ref, out, e))
        keys = _row_keys(start, len(vectors))
        pos = np.arange(start, start + len(vectors))
        if self.sample is not None:
            k0, p0, v0, o0 = self.sample
            keys, pos = np.concatenate([k0, keys]), np.concatenate([p0, pos])
            vectors, out = _concat([v0, vectors]), np.concatenate([o0, out])
        if len(keys) > DIAGNOSIS_ROWS:
            keep = np.sort(np.argsort(keys, kind="stable")[:DIAGNOSIS_ROWS])
            keys, pos, vectors, out = keys[keep], pos[keep], vectors.subset(keep), out[keep]
        self.sample = (keys, pos, vectors, out)

    def result(self, tolerance, n_skipped):
        with np.errstate(all="ignore"):  # the diagnosis fits the submitted values, as add()
            return self._result(tolerance, n_skipped)

    def _result(self, tolerance, n_skipped):
        if self.n == 0:
            raise ValueError("vectors: nothing to grade (0 rows)")
        rel, ab = self.rel, self.ab
        passed = bool(self.finite and self.max_norm <= 1.0)
        g = Grade(
            quantity="values",
            measured=self.max_norm,
            threshold=1.0,
            unit="x tolerance",
            tier=CONFORMS if passed else DOES_NOT_CONFORM,
            max_abs_error=self.max_abs if self.finite else math.inf,
            rms_error=self.scale * math.sqrt(self.sum_sq / self.n_values) if self.finite else math.inf,
            tolerance={"relative": rel, "absolute": ab, "rule": "|out - ref| <= absolute + relative |ref|"},
            tolerance_reason=TOLERANCE_REASON if tolerance is None else "tolerance given by the caller",
            worst=[t[2] for t in self.worst],
            n_rows=self.n,
            n_failed_rows=self.n_failed,
            max_rel_error=self.max_rel if self.finite else math.inf,
            max_normalised_error=self.max_norm,
            models=sorted(self.models),
            version=self.version,
            regions=sorted(self.regions.values(), key=lambda r: _region_names().index(r["region"])),
            n_nan=self.n_nan,
            n_inf=self.n_inf,
            n_skipped=int(n_skipped),
        )
        from .properties import vector_properties

        g.properties = vector_properties(self.sample[2], self.sample[3], rel, ab, self.half)
        if passed:
            g.diagnosis_detail = "conforms: every value within the tolerance"
            return g
        _, _, vectors, out = self.sample
        ref = accepted_reference(vectors, out, ab)
        e = _normalised(out, ref, rel, ab)
        # NaN/Inf rows and values below the horizon are named on their own; the rest is fitted
        # on the finite rows above the horizon, so that neither masks another bug
        finite = np.isfinite(out).all(axis=1)
        failing = e.max(axis=1) > 1.0
        below = _below_horizon(vectors) & finite & failing
        rest = finite & ~below
        names, texts = [], []
        if self.n_nonfinite_rows:
            names.append("non_finite_output")
            texts.append(_nonfinite_text(self.nonfinite, self.n_nonfinite_rows, g.n_nan, g.n_inf))
        if below.any():
            names.append("nonzero_below_horizon")
            texts.append(_below_text(vectors.subset(below), out[below]))
        explained = True
        if (rest & failing).any():
            sub = vectors.subset(rest)
            singles = []
            (name, detail, g.candidates, g.candidate_details, g.candidate_match_fractions) = _diagnose(
                sub, out[rest], ref[rest], e[rest], rel, ab, singles
            )
            # a named deviation that explains half the failing values or more: structure,
            # not precision noise (the rest is another effect, left unexplained)
            partly = max(g.candidate_match_fractions.values(), default=0.0) >= 0.5
            if name is None and not partly:
                prec = _precision(sub, out[rest], ref[rest], rel, ab)
                if prec is not None:
                    name, detail = "precision", prec
            if name is None:
                g.closest = _closest(singles, out[rest], ref[rest], rel, ab)
            explained = name is not None
            if explained:
                names.append(name)
                texts.append(detail)
        from .terms import which_term

        g.terms = which_term(vectors.subset(rest), out[rest], rel, ab)
        g.diagnosis = " & ".join(names) if explained and names else None
        g.diagnosis_detail = "; ".join(texts)
        if len(vectors) < self.n:
            g.diagnosis_detail += f" (fitted on a sample of {len(vectors)} of the {self.n} rows)"
        if self.finite and self.half and self.max_norm_half <= 1.0:
            g.tier = CONFORMS_WITH_WARNINGS
            g.warnings.append(
                "half precision declared: every value within the tolerance plus 1 ulp of float16 at the "
                f"reference (the values are off by up to {self.max_norm:.3g} tolerances: float16 rounding)"
            )
        elif self.finite and g.diagnosis in WARNING_DEVIATIONS:
            g.tier = CONFORMS_WITH_WARNINGS
            g.warnings.append(
                f"{g.diagnosis}: {WARNING_DEVIATIONS[g.diagnosis]}; max relative error {g.max_rel_error:.2g}"
            )
        if g.diagnosis is None:
            where = where_it_fails(g.regions)
            nonfinite = ", ".join(f"{n} {w} values" for n, w in ((g.n_nan, "NaN"), (g.n_inf, "Inf")) if n)
            near = closest_text(g.closest) if g.closest else ""
            g.diagnosis_detail = ". ".join(x for x in (NOT_EXPLAINED, near, where, nonfinite, *texts) if x)
        return g


def grade_chunks(
    chunks: Iterable[tuple[VectorSet, np.ndarray] | tuple[VectorSet, np.ndarray, int]],
    *,
    model: str | None = None,
    tolerance: float | tuple | None = None,
    precision: str | None = None,
) -> Grade:
    """Grade ``(vectors, out[, n_skipped])`` chunks (e.g. :func:`.vectors.iter_results`) as one
    file: the same :class:`Grade` as :func:`grade` on the rows put together (the diagnosis is
    fitted on a sample of :data:`DIAGNOSIS_ROWS` rows when there are more); memory is bounded
    by the chunk size.

    Examples
    --------
    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> from openpbr_diffuse.conformance.deviations import reference
    >>> v = default_vectors()
    >>> parts = [(v.subset(slice(k, k + 500)), reference(v.subset(slice(k, k + 500)))) for k in range(0, len(v), 500)]
    >>> grade_chunks(parts).passed
    True
    """
    rel, ab = _tolerance(tolerance)
    acc = _Accumulator(rel, ab, precision)
    skipped = 0
    seen_model = False
    for chunk in chunks:
        vectors, out = chunk[0], np.asarray(chunk[1], dtype=np.float64)
        skipped += int(chunk[2]) if len(chunk) > 2 else 0
        if out.shape != (len(vectors), 3):
            raise ValueError(f"out must have shape ({len(vectors)}, 3) (one RGB value per vector), got {out.shape}")
        if model is not None:
            keep = vectors.model == model
            seen_model |= bool(keep.any())
            vectors, out = vectors.subset(keep), out[keep]
        acc.add(vectors, out)
    if model is not None and not seen_model:
        raise ValueError(f"model: no rows of model {model!r}")
    return acc.result(tolerance, skipped)


__all__ = [
    "grade",
    "grade_chunks",
    "Grade",
    "DIAGNOSIS_ROWS",
    "REL_TOL",
    "ABS_TOL",
    "TOLERANCE_REASON",
    "NOT_EXPLAINED",
    "OUT_OF_RANGE",
    "region_masks",
    "where_it_fails",
    "accepted_reference",
    "CONFORMS",
    "CONFORMS_WITH_WARNINGS",
    "DOES_NOT_CONFORM",
    "WARNING_DEVIATIONS",
    "ulp_half",
    "closest_text",
    "CLOSEST_FACTOR",
]
