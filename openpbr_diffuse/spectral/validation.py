"""Spectral versus RGB evaluation of EON's colour shift, and the white-then-tint mode.

EON's multiple-scattering albedo rho_ms = rho^2 <E_F> / (1 - rho (1 - <E_F>)) (Eq. 18) is
nonlinear in rho, so the directional albedo E(mu) = rho E_F(mu) + rho_ms (1 - E_F(mu))
(Eq. 20) of a coloured surface depends on whether it is evaluated per wavelength or per RGB
channel, and "white then tint" (rho E(mu; rho = 1)) removes the shift altogether.  For every
colour x roughness x mu this module computes (names as in the JSON output):

- ``rho_rgb``: the colour's Lambertian albedo (its reflectance), working-space RGB;
- ``albedo_spectral``: EON albedo (reference colour mode) per wavelength -> XYZ -> RGB;
- ``albedo_rgb``: EON albedo per RGB channel of ``rho_rgb`` (clipped to [0, 1] if the colour
  is out of the working-space gamut: ``rho_rgb_clipped``);
- ``albedo_white_tint``: rho(lambda) E(mu; rho = 1) per wavelength -> RGB;
- ``delta_e_rgb_vs_spectral`` = CIEDE2000(albedo_rgb, albedo_spectral), with
  ``rel_luminance_diff_rgb_vs_spectral`` = Y_rgb / Y_spectral - 1 and
  ``chroma_diff_rgb_vs_spectral`` = C*ab_rgb - C*ab_spectral;
- ``delta_e_shift`` = CIEDE2000(albedo_spectral, albedo_white_tint) (the colour shift), with
  ``rel_luminance_diff_shift`` = Y_spectral / Y_white_tint - 1 and
  ``chroma_diff_shift`` = C*ab_spectral - C*ab_white_tint.

The albedos come from ``openpbr_diffuse.directional_albedo("eon", ...)`` with the spectral
samples (or RGB channels) as its channel axis; colorimetry from ``colorimetry.Colorimetry``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar
from ..models import directional_albedo
from .colorimetry import colorimetry as _make_colorimetry

if TYPE_CHECKING:
    from .colorimetry import Colorimetry
    from .colorsets import ColourSet

MODEL = "eon"
DEFAULT_ROUGHNESS = (0.0, 0.25, 0.5, 0.75, 1.0)
DEFAULT_MU = (0.2, 0.5, 1.0)
#: the per-row scalar fields, in output order.
SCALAR_FIELDS = (
    "delta_e_rgb_vs_spectral",
    "rel_luminance_diff_rgb_vs_spectral",
    "chroma_diff_rgb_vs_spectral",
    "delta_e_shift",
    "rel_luminance_diff_shift",
    "chroma_diff_shift",
)
RGB_FIELDS = ("rho_rgb", "albedo_spectral", "albedo_rgb", "albedo_white_tint")


@dataclass
class ColourShift:
    """Results on the grid colours (P) x roughness (K) x mu (M).

    Arrays ``rho_rgb`` (P, 3); ``albedo_*`` (P, K, M, 3) working-space RGB; ``XYZ_*`` and
    ``Lab_*`` (P, K, M, 3) for "spectral", "rgb", "white_tint"; the SCALAR_FIELDS (P, K, M).
    """

    colours: ColourSet
    roughness: np.ndarray
    mu: np.ndarray
    colorimetry: Colorimetry
    rho_rgb: np.ndarray
    rho_rgb_clipped: np.ndarray
    albedo_spectral: np.ndarray
    albedo_rgb: np.ndarray
    albedo_white_tint: np.ndarray
    XYZ: dict
    Lab: dict
    delta_e_rgb_vs_spectral: np.ndarray
    rel_luminance_diff_rgb_vs_spectral: np.ndarray
    chroma_diff_rgb_vs_spectral: np.ndarray
    delta_e_shift: np.ndarray
    rel_luminance_diff_shift: np.ndarray
    chroma_diff_shift: np.ndarray

    def settings(self) -> dict[str, Any]:
        """The settings used, as plain data."""
        d = {
            "model": MODEL,
            "color_mode_spectral": "reference",
            "color_mode_white_tint": "white_tint",
            "roughness": self.roughness.tolist(),
            "mu": self.mu.tolist(),
        }
        d.update(self.colorimetry.describe())
        d["fields"] = {
            "rho_rgb": "the colour's reflectance (Lambertian albedo), working-space linear RGB",
            "albedo_spectral": "EON directional albedo per wavelength (reference colour mode) -> RGB",
            "albedo_rgb": "EON directional albedo per RGB channel of rho_rgb (clipped to [0, 1]: rho_rgb_clipped)",
            "albedo_white_tint": "rho(lambda) * EON albedo at rho = 1, per wavelength -> RGB",
            "delta_e_rgb_vs_spectral": "CIEDE2000(albedo_rgb, albedo_spectral)",
            "rel_luminance_diff_rgb_vs_spectral": "Y(albedo_rgb) / Y(albedo_spectral) - 1",
            "chroma_diff_rgb_vs_spectral": "C*ab(albedo_rgb) - C*ab(albedo_spectral)",
            "delta_e_shift": "CIEDE2000(albedo_spectral, albedo_white_tint): the colour shift",
            "rel_luminance_diff_shift": "Y(albedo_spectral) / Y(albedo_white_tint) - 1",
            "chroma_diff_shift": "C*ab(albedo_spectral) - C*ab(albedo_white_tint)",
            "roundtrip_delta_e": "CIEDE2000 between rho_rgb and the colour of the spectrum used (null: measured)",
        }
        return d

    def rows(self) -> list[dict[str, Any]]:
        """One dict per colour x roughness x mu (the JSON ``rows``), floats rounded to 1e-9."""
        cs = self.colours
        out = []
        for p, k, m in np.ndindex(self.delta_e_shift.shape):
            de = cs.roundtrip_delta_e[p]
            row = {
                "patch": cs.names[p],
                "source": cs.source[p],
                "roughness": float(self.roughness[k]),
                "mu": float(self.mu[m]),
                "rho_rgb": _r(self.rho_rgb[p]),
                "rho_rgb_clipped": bool(self.rho_rgb_clipped[p]),
            }
            for name in RGB_FIELDS[1:]:
                row[name] = _r(getattr(self, name)[p, k, m])
            for name in SCALAR_FIELDS:
                row[name] = _r(getattr(self, name)[p, k, m])
            row["roundtrip_delta_e"] = None if np.isnan(de) else _r(de)
            row.update(cs.extra[p])
            out.append(row)
        return out

    def summary(self, roughness: float = 1.0) -> dict[float, dict[str, dict[str, tuple[Any, Any]]]]:
        """Largest and median ``delta_e_rgb_vs_spectral`` and ``delta_e_shift`` at ``roughness``, per mu.

        Returns {mu: {field: {"max": (value, patch), "max_in_gamut": (value, patch),
        "median": (value, "patch / patch")}}}: "max_in_gamut" leaves out colours whose
        ``rho_rgb`` was clipped; for an even count the median is the mean of the two middle
        values, and both patches are named.
        """
        k = int(np.argmin(abs(self.roughness - roughness)))
        if abs(self.roughness[k] - roughness) > 1e-12:
            raise ValueError(f"roughness {roughness} is not on the grid {self.roughness.tolist()}")
        names = self.colours.names
        inside = np.flatnonzero(~self.rho_rgb_clipped)
        out: dict[float, dict[str, dict[str, tuple[Any, Any]]]] = {}
        for m, mu in enumerate(self.mu):
            out[float(mu)] = {}
            for name in ("delta_e_rgb_vs_spectral", "delta_e_shift"):
                v = getattr(self, name)[:, k, m]
                order = np.argsort(v, kind="stable")
                mid = sorted({order[(len(v) - 1) // 2], order[len(v) // 2]})
                best_in = inside[int(np.argmax(v[inside]))] if inside.size else None
                out[float(mu)][name] = {
                    "max": (float(v[order[-1]]), names[order[-1]]),
                    "max_in_gamut": (None, None) if best_in is None else (float(v[best_in]), names[best_in]),
                    "median": (float(np.median(v)), " / ".join(names[i] for i in mid)),
                }
        return out


def _r(v):
    v = np.asarray(v, np.float64)
    return round(float(v), 9) if v.ndim == 0 else [round(float(x), 9) for x in v]


def _relative(a, b):
    """a / b - 1, defined as 0 where both are 0 (a black colour: no difference, not NaN)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where((a == 0) & (b == 0), 0.0, a / b - 1.0)


def _grid(name: str, values: ArrayLike, lo: float, hi: float) -> NDArray[np.float64]:
    a = np.atleast_1d(np.asarray(values, np.float64))
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"{name} must be a non-empty list of numbers")
    ar.in_range(name, a, np.float64, lo, hi, "")
    return a


def colour_shift(
    colours: ColourSet,
    roughness: ArrayLike = DEFAULT_ROUGHNESS,
    mu: ArrayLike = DEFAULT_MU,
    cm: Colorimetry | None = None,
) -> ColourShift:
    """Spectral vs RGB vs white-then-tint EON albedo for a colour set on a roughness x mu grid.

    Parameters
    ----------
    colours : ColourSet
        From ``colorsets.checker``, ``from_rgb``, ``from_spectra_csv`` or ``from_materials``
        (built with the same ``cm``).
    roughness : array_like, shape (K,)
        EON roughness r in [0, 1].
    mu : array_like, shape (M,)
        Cosine of the view angle, in [0, 1].
    cm : Colorimetry, optional
        Default: D65, lin_rec709, 380-780 nm / 5 nm.

    Returns
    -------
    ColourShift

    Examples
    --------
    >>> from openpbr_diffuse.spectral.colorsets import checker
    >>> from openpbr_diffuse.spectral.colorimetry import colorimetry
    >>> cm = colorimetry()
    >>> res = colour_shift(checker(cm), roughness=[0.0, 1.0], mu=[1.0], cm=cm)
    >>> inside = ~res.rho_rgb_clipped                  # 'cyan' is outside Rec.709: clipped
    >>> float(res.delta_e_rgb_vs_spectral[inside, 0].max()) < 1e-9     # r = 0: EON is Lambert
    True
    >>> bool(res.delta_e_shift[:, 1].max() > 1.0)                 # r = 1: a visible shift
    True
    """
    cm = cm or _make_colorimetry()
    r = _grid("roughness", roughness, 0.0, 1.0)
    mu = _grid("mu", mu, 0.0, 1.0)
    S = colours.spectra
    if S.shape[-1] != cm.wavelengths.size:
        raise ValueError("colours were built for another spectral shape than cm")
    rgb = colours.rho_rgb
    rgb_eval = np.clip(rgb, 0.0, 1.0)
    clipped = np.any(rgb_eval != rgb, axis=-1)
    lead = (slice(None), None, None)
    rr, mm = r[None, :, None], mu[None, None, :]
    # one albedo call (one compiled kernel variant to load): the N spectral samples, the 3 RGB
    # channels and a white channel rho = 1, whose albedo times rho(lambda) is white then tint
    # (the definition of color_mode="white_tint")
    n = S.shape[-1]
    channels = np.concatenate([S, rgb_eval, np.ones((len(S), 1))], axis=-1)
    E = directional_albedo(MODEL, mm, rr, channels[lead], color_mode="reference")
    E_spec, E_rgb, E_tint = E[..., :n], E[..., n : n + 3], S[lead] * E[..., n + 3 :]
    XYZ = {"spectral": cm.spectra_to_XYZ(E_spec), "white_tint": cm.spectra_to_XYZ(E_tint), "rgb": cm.RGB_to_XYZ(E_rgb)}
    Lab = {k: cm.XYZ_to_Lab(v) for k, v in XYZ.items()}
    C = {k: cm.chroma(v) for k, v in Lab.items()}
    Y = {k: v[..., 1] for k, v in XYZ.items()}
    rel_rgb, rel_shift = _relative(Y["rgb"], Y["spectral"]), _relative(Y["spectral"], Y["white_tint"])
    return ColourShift(
        colours,
        r,
        mu,
        cm,
        rgb,
        clipped,
        cm.XYZ_to_RGB(XYZ["spectral"]),
        E_rgb,
        cm.XYZ_to_RGB(XYZ["white_tint"]),
        XYZ,
        Lab,
        cm.delta_E(Lab["rgb"], Lab["spectral"]),
        rel_rgb,
        C["rgb"] - C["spectral"],
        cm.delta_E(Lab["spectral"], Lab["white_tint"]),
        rel_shift,
        C["spectral"] - C["white_tint"],
    )
