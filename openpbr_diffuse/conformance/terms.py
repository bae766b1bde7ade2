"""Which term of EON is wrong: the failing values decomposed along the model's structure.

EON is f = f_ss + f_ms (Eq. 16): the single-scattering FON lobe (A_F, B_F, the s > 0 and
s ≤ 0 branches, t = max(μ_i, μ_o)) plus the multiple-scattering lobe (E_F, ⟨E_F⟩, ρ_ms and the
(1 − E_F(μ_i))(1 − E_F(μ_o)) shape); the albedo is ρ E_F + ρ_ms (1 − E_F) likewise.  Both
terms are the library's own (FON for f_ss, EON − FON for f_ms).  :func:`which_term` fits the
submitted values of the failing rows as a·f_ss + b·f_ms (least squares), splits the BRDF rows
by branch (s > 0 and s ≤ 0) and roughness 0 (where f_ms = 0), and, when no constant pair of
factors fits, says which quantity the ratio of each term follows.
"""

from __future__ import annotations

import numpy as np

from .vectors import VectorSet

_EON = ("eon", "eon_approx")
#: a fitted factor within this of 1 "matches"
_MATCH = 1e-3
#: |correlation| above which the ratio of a term is said to follow a quantity
_FOLLOWS = 0.9


def _fmt_factor(k: float) -> str:
    return f"{k:.6g}x" if abs(k - 1.0) < 1e-3 else f"{k:.4g}x"


def which_term(vectors: VectorSet, out: np.ndarray, rel: float = 1e-4, ab: float = 1e-6) -> str | None:
    """A sentence saying which EON term the failing values of ``out`` get wrong, or None (no
    failing EON row above the horizon with a finite value).

    Examples
    --------
    f_ms 1.18x too large on every EON row:

    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> from openpbr_diffuse.conformance.deviations import reference, _single_scattering
    >>> v = default_vectors(["eon"])
    >>> ss = _single_scattering(v)
    >>> print(which_term(v, ss + 1.18 * (reference(v) - ss)))  # doctest: +ELLIPSIS
    the error is in the multiple-scattering term: f_ss matches (1x), f_ms is 1.18x off, constant across ... rows; every roughness-0 row matches (Lambert): the error grows with roughness
    """
    from .deviations import _single_scattering, reference

    out = np.asarray(out, np.float64)
    brdf = vectors.kind == "brdf"
    up = ~brdf | ((vectors.wi[:, 2] > 0) & (vectors.wo[:, 2] > 0))
    sel = np.isin(vectors.model, _EON) & up & np.isfinite(out).all(axis=1)
    if not sel.any():
        return None
    v, y = vectors.subset(sel), out[sel]
    with np.errstate(all="ignore"):
        ref = reference(v)
        ss = _single_scattering(v)
        ms = ref - ss
        tol = ab + rel * np.abs(ref)
        bad = (np.abs(y - ref) > tol).any(axis=1)
        if not bad.any():
            return None
        parts = []
        b_rows = v.kind == "brdf"
        s = np.einsum("ij,ij->i", v.wi, v.wo) - v.wi[:, 2] * v.wo[:, 2]
        branch = _branches(bad, b_rows, s, v.roughness)
        # a y = a ss + b ms fit on the failing rows, weighted by the tolerance
        w = 1.0 / tol[bad].ravel()
        X = np.stack([ss[bad].ravel(), ms[bad].ravel()], axis=1) * w[:, None]
        has_ms = bool(np.any(np.abs(ms[bad]) > tol[bad]))
        if not has_ms:
            X = X[:, :1]
        coef, *_ = np.linalg.lstsq(X, y[bad].ravel() * w, rcond=None)
        a = float(coef[0])
        b = float(coef[1]) if has_ms else 1.0
        resid = float(np.max(np.abs(X @ coef - y[bad].ravel() * w)))
        n = int(bad.sum())
        if resid <= 2.0:
            a_ok, b_ok = abs(a - 1.0) <= _MATCH, abs(b - 1.0) <= _MATCH
            if a_ok and not b_ok:
                parts.append(
                    f"the error is in the multiple-scattering term: f_ss matches ({_fmt_factor(a)}), "
                    f"f_ms is {_fmt_factor(b)} off, constant across {n} failing rows"
                )
            elif b_ok and not a_ok:
                parts.append(
                    f"the error is in the single-scattering term: f_ss is {_fmt_factor(a)} off, f_ms matches "
                    f"({_fmt_factor(b)}), constant across {n} failing rows"
                )
            elif abs(a - b) <= _MATCH * max(1.0, abs(a)):
                parts.append(f"both terms are {_fmt_factor(a)} off: a factor on the whole value")
            else:
                parts.append(f"f_ss is {_fmt_factor(a)} off and f_ms {_fmt_factor(b)}, each constant across {n} rows")
        else:
            # f_ms does not depend on the azimuth: an error in one s branch only is in f_ss
            parts.append(_ratios(v, y, ss, ms, bad, tol, ss_only="branch fails" in branch))
        if branch:
            parts.append(branch)
    return "; ".join(p for p in parts if p)


def _branches(bad, b_rows, s, r):
    """Which BRDF rows fail: the s > 0 branch, the s <= 0 branch, or only rows with r > 0."""
    pos, neg = b_rows & (s > 1e-12), b_rows & (s < -1e-12)
    fp, fn = int((bad & pos).sum()), int((bad & neg).sum())
    words = []
    if pos.any() and neg.any() and (fp + fn):
        if fn == 0:
            words.append(
                f"only the s > 0 branch fails ({fp} of {int(pos.sum())} rows; every s < 0 row matches): "
                "look at s/t with t = max(mu_i, mu_o)"
            )
        elif fp == 0:
            words.append(
                f"only the s <= 0 branch fails ({fn} of {int(neg.sum())} rows; every s > 0 row matches): "
                "look at s/t = s there (t = 1)"
            )
    zero = b_rows & (r == 0)
    if zero.any() and not (bad & zero).any() and (bad & b_rows).any():
        words.append("every roughness-0 row matches (Lambert): the error grows with roughness")
    return "; ".join(words)


def _ratios(v, y, ss, ms, bad, tol, ss_only=False):
    """When no constant pair of factors fits: what the ratio of each term follows."""
    from .deviations import _eon_parts

    _, _, e_i, e_o, avg, _ = _eon_parts(v)
    b = v.kind == "brdf"
    one = np.ones(3)
    quantities = {
        "1 - E_F(mu_i)": np.outer(1.0 - e_i, one),
        "1 - E_F(mu_o)": np.outer(1.0 - e_o, one),
        "roughness": np.outer(v.roughness, one),
        "<E_F>": np.outer(avg, one),
        "rho": v.rho,
    }
    words = []
    terms = (("f_ss", ss, ms),) if ss_only else (("f_ms", ms, ss), ("f_ss", ss, ms))
    for term, mine, other in terms:
        ok = bad[:, None] & (np.abs(mine) > 10 * tol)
        if ok.sum() < 3:
            continue
        kr = ((y - other) / np.where(ok, mine, 1.0))[ok]
        if not np.all(np.isfinite(kr)) or np.std(kr) <= _MATCH * max(1.0, abs(np.mean(kr))):
            continue
        best = None
        for name, q in quantities.items():
            qq = q[ok]
            good = np.isfinite(qq) & (qq > 0) & (kr > 0)
            if good.sum() < 3 or np.std(np.log(qq[good])) == 0:
                continue
            c = float(np.corrcoef(np.log(kr[good]), np.log(qq[good]))[0, 1])
            if abs(c) >= _FOLLOWS and (best is None or abs(c) > abs(best[1])):
                best = (name, c)
        rng = f"{kr.min():.3g} to {kr.max():.3g}"
        if best is not None:
            power = "1/" if best[1] < 0 else ""
            words.append(
                f"{term} is {rng}x the reference's, following {power}({best[0]}) (correlation {best[1]:.2f})"
                + (" -- a factor of f_ms missing or extra" if term == "f_ms" else "")
            )
        elif ss_only:
            words.append(f"the error is in the single-scattering term f_ss ({rng}x the reference's where it fails)")
        else:
            words.append(f"{term} is {rng}x the reference's, varying from row to row")
        if term == "f_ms" and b.any():
            break
    return "; ".join(words) or "no pair of constant factors on f_ss and f_ms fits the failing rows"


__all__ = ["which_term"]
