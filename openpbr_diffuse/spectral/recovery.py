"""RGB -> reflectance spectrum upsampling through ``colour.recovery`` (a method table).

The target of every method is the same: a reflectance spectrum in [0, 1] whose colour,
taken through this package's pipeline (XYZ under the chosen illuminant, Bradford to the
working space), is the given working-space RGB.  How close each method gets is its
round-trip error, reported per colour (``roundtrip_delta_e``, CIEDE2000).

Methods (``RECOVERY_METHODS``; cost measured on the 2-core development VM):

- ``"Mallett 2019"``: a non-negative combination of three basis spectra fitted to the
  linear Rec.709 primaries under D65 (Mallett & Yuksel 2019); vectorised, ~0.5 ms per call.
  Only colours inside the Rec.709 gamut [0, 1]^3 (after conversion from the working space)
  have a spectrum in [0, 1]; others raise ``ValueError``.  Exact at D65 + lin_rec709 up to
  the basis fit; under other illuminants the round trip is only approximate (reported).
- ``"Otsu 2018"``: Otsu, Yamamoto & Hachisuka 2018, a PCA basis per cluster of measured
  reflectances, solved for the XYZ under the chosen illuminant; ~4 ms per colour; its
  native shape is 380-730 nm / 10 nm (aligned here, constant extrapolation); clipped to [0, 1].
- ``"Jakob 2019"``: Jakob & Hanika 2019, the sigmoid of a quadratic, optimised per colour
  (``colour.recovery.XYZ_to_sd_Jakob2019``, ~80 ms per colour).  colour-science builds its
  fast 3-D LUT only by running this optimisation over a whole RGB cube (hours), so the per-colour
  optimisation is what is used here; spectra are in (0, 1) by construction.

``"auto"`` (the default) picks Mallett 2019 for the lin_rec709 working space and Otsu 2018
otherwise.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .colorimetry import _colour

if TYPE_CHECKING:
    from .colorimetry import Colorimetry


def _mallett2019(rgb, cm):
    colour = _colour()
    space = colour.RGB_COLOURSPACES["ITU-R BT.709"]
    rgb709 = colour.XYZ_to_RGB(
        cm.RGB_to_XYZ(rgb) / 100.0, space, illuminant=cm.white_xy, chromatic_adaptation_transform="Bradford"
    )
    eps = 1e-9
    bad = np.any((rgb709 < -eps) | (rgb709 > 1.0 + eps), axis=-1)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise ValueError(
            f"colour {np.round(rgb[i], 6).tolist()} ({cm.working_space}) is outside the "
            f"linear Rec.709 gamut [0, 1] (Rec.709 RGB {np.round(rgb709[i], 6).tolist()}): "
            f"method 'Mallett 2019' cannot upsample it; use 'Otsu 2018' or 'Jakob 2019'"
        )
    basis = colour.recovery.MSDS_BASIS_FUNCTIONS_sRGB_MALLETT2019.copy().align(cm.colour_shape)
    # the spectrum is linear in RGB: rgb709 @ basis^T, evaluated by colour-science per colour
    # would be the same product; one matrix product keeps it vectorised
    return np.clip(np.clip(rgb709, 0.0, 1.0) @ np.asarray(basis.values).T, 0.0, 1.0)


def _per_colour(method):
    def recover(rgb, cm):
        colour = _colour()
        XYZ = cm.RGB_to_XYZ(rgb) / 100.0
        out = np.empty(rgb.shape[:-1] + (cm.wavelengths.size,))
        # the colour.recovery solvers take one colour at a time; their notices about
        # trimming / re-shaping to their native shapes are expected (see the module notes)
        with colour.utilities.suppress_warnings(colour_runtime_warnings=True):
            for i in np.ndindex(rgb.shape[:-1]):
                sd = colour.XYZ_to_sd(XYZ[i], method=method, illuminant=cm.illuminant_sd, cmfs=cm.cmfs)
                out[i] = sd.copy().align(cm.colour_shape).values
        return np.clip(out, 0.0, 1.0)

    return recover


#: method name -> function(rgb (..., 3) working-space linear, Colorimetry) -> spectra (..., N) in [0, 1].
RECOVERY_METHODS = {
    "Mallett 2019": _mallett2019,
    "Otsu 2018": _per_colour("Otsu 2018"),
    "Jakob 2019": _per_colour("Jakob 2019"),
}
#: working space -> method used by ``method="auto"``.
AUTO_METHOD = {"lin_rec709": "Mallett 2019"}
DEFAULT_AUTO = "Otsu 2018"


def resolve_method(method: str, cm: Colorimetry) -> str:
    """The method name ``method`` stands for (``"auto"`` depends on the working space)."""
    if not isinstance(method, str):
        raise TypeError(f"method must be a string, got {type(method).__name__}")
    if method == "auto":
        return AUTO_METHOD.get(cm.working_space, DEFAULT_AUTO)
    if method not in RECOVERY_METHODS:
        raise ValueError(f"method must be 'auto' or one of {', '.join(RECOVERY_METHODS)}; got {method!r}")
    return method


def check_rgb(name: str, rgb: ArrayLike) -> NDArray[np.float64]:
    """``rgb`` as a float64 array (..., 3) of finite values in [0, 1], else ValueError/TypeError."""
    try:
        a = np.asarray(rgb, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be numbers, shape (..., 3)") from None
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) (R, G, B), got {a.shape}")
    if not np.all(np.isfinite(a)) or np.any((a < 0.0) | (a > 1.0)):
        raise ValueError(f"{name} must be working-space linear RGB reflectances in [0, 1], got {a.tolist()}")
    return a


def rgb_to_spectra(
    rgb: ArrayLike, cm: Colorimetry, method: str = "auto"
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Upsample working-space linear RGB reflectances to spectra on ``cm.wavelengths``.

    Parameters
    ----------
    rgb : array_like, shape (..., 3), values in [0, 1]
    cm : Colorimetry
    method : str
        "auto" or a key of ``RECOVERY_METHODS``.

    Returns
    -------
    spectra : ndarray, shape (..., N), in [0, 1]
    roundtrip_delta_e : ndarray, shape (...)
        CIEDE2000 between the colour of ``rgb`` and that of the spectrum (same pipeline).

    Examples
    --------
    >>> from openpbr_diffuse.spectral.colorimetry import colorimetry
    >>> s, de = rgb_to_spectra([[0.5, 0.5, 0.5]], colorimetry())
    >>> s.shape, bool(abs(s - 0.5).max() < 1e-3), bool(de[0] < 0.01)
    ((1, 81), True, True)
    """
    rgb = check_rgb("rgb", rgb)
    name = resolve_method(method, cm)
    spectra = RECOVERY_METHODS[name](rgb, cm)
    return spectra, roundtrip_delta_e(rgb, spectra, cm)


def roundtrip_delta_e(rgb: ArrayLike, spectra: ArrayLike, cm: Colorimetry) -> NDArray[np.float64]:
    """CIEDE2000 between working-space RGB colours and the colours of their spectra."""
    return cm.delta_E(cm.XYZ_to_Lab(cm.RGB_to_XYZ(rgb)), cm.XYZ_to_Lab(cm.spectra_to_XYZ(spectra)))
