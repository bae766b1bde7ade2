"""Colorimetry of the spectral validation: spectra -> XYZ -> working-space RGB -> CIELAB.

Everything colorimetric is computed by colour-science (imported here, lazily: this module
is only imported when a spectral feature runs):

- XYZ: ``colour.msds_to_XYZ(..., method="Integration")`` with the CIE 1931 2 degree
  observer and the chosen illuminant, both aligned to one ``colour.SpectralShape``
  (default 380-780 nm every 5 nm, 81 samples); k normalises the perfect reflector to
  Y = 100.
- RGB: ``colour.XYZ_to_RGB`` / ``colour.RGB_to_XYZ`` with Bradford chromatic adaptation
  from the illuminant's white to the working space's white (as OCIO, OIIO and USD do).
- CIELAB: ``colour.XYZ_to_Lab`` with the illuminant's own white (its XYZ under the same
  observer) as the reference white; ``colour.delta_E(..., method="CIE 2000")``.

Working spaces are a table (``WORKING_SPACES``: name -> colour-science colourspace), not an
if-chain; so are illuminants (any name of ``colour.SDS_ILLUMINANTS``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._colour import _colour  # colour-science, imported on first use

#: working-space name (as on the command line) -> colour-science RGB colourspace name.
#: All are scene-linear (no transfer function is applied).
WORKING_SPACES = {
    "lin_rec709": "ITU-R BT.709",
    "acescg": "ACEScg",
    "lin_rec2020": "ITU-R BT.2020",
    "lin_p3d65": "P3-D65",
}
#: other spellings (case-insensitive: MaterialX / OCIO / USD names) -> working-space name.
WORKING_SPACE_ALIASES = {
    "rec709": "lin_rec709",
    "lin_srgb": "lin_rec709",
    "srgb_linear": "lin_rec709",
    "linear": "lin_rec709",
    "lin_rec709_scene": "lin_rec709",
    "linear rec.709 (srgb)": "lin_rec709",
    "aces_cg": "acescg",
    "lin_ap1": "acescg",
    "lin_ap1_scene": "acescg",
    "ap1": "acescg",
    "rec2020": "lin_rec2020",
    "lin_rec2020_scene": "lin_rec2020",
    "linear rec.2020": "lin_rec2020",
    "p3d65": "lin_p3d65",
    "lin_p3d65_scene": "lin_p3d65",
    "linear p3-d65": "lin_p3d65",
}
DEFAULT_WORKING_SPACE = "lin_rec709"
DEFAULT_ILLUMINANT = "D65"
OBSERVER = "CIE 1931 2 Degree Standard Observer"
CAT = "Bradford"
#: (start, end, interval) in nm of the default spectral shape: 81 samples.
DEFAULT_SHAPE = (380.0, 780.0, 5.0)


def illuminant_names() -> list[str]:
    """Names accepted for ``illuminant`` (those of ``colour.SDS_ILLUMINANTS``)."""
    return sorted(_colour().SDS_ILLUMINANTS.keys())


@dataclass(frozen=True, eq=False)
class Colorimetry:
    """The colorimetric set-up: spectral shape, observer, illuminant and working space.

    Build with ``colorimetry(illuminant, working_space, shape)``; instances are cached.

    Attributes
    ----------
    illuminant, working_space : str
        The names given (validated).
    shape : tuple of float
        (start, end, interval) in nm.
    wavelengths : ndarray, shape (N,)
    white_XYZ : ndarray, shape (3,)
        XYZ of the perfect reflector under the illuminant (Y = 100): the CIELAB reference white.
    white_xy : ndarray, shape (2,)
        Its chromaticity, the source white of the Bradford adaptation.
    """

    illuminant: str
    working_space: str
    shape: tuple
    wavelengths: np.ndarray
    white_XYZ: np.ndarray
    white_xy: np.ndarray
    _cmfs: object
    _illuminant_sd: object
    _space: Any

    @property
    def cmfs(self) -> Any:
        """The CIE 1931 2 degree colour-matching functions aligned to ``shape`` (colour-science)."""
        return self._cmfs

    @property
    def illuminant_sd(self) -> Any:
        """The illuminant's spectral distribution aligned to ``shape`` (colour-science)."""
        return self._illuminant_sd

    @property
    def colour_shape(self) -> Any:
        return _colour().SpectralShape(*self.shape)

    def describe(self) -> dict[str, Any]:
        """The settings as plain data (for JSON output and table headers)."""
        start, end, interval = self.shape
        return {
            "illuminant": self.illuminant,
            "observer": OBSERVER,
            "working_space": self.working_space,
            "working_space_colour_science": self._space.name,
            "working_space_white_xy": [float(v) for v in self._space.whitepoint],
            "chromatic_adaptation": f"{CAT} (illuminant white -> working-space white)",
            "spectral_shape": {
                "start_nm": start,
                "end_nm": end,
                "interval_nm": interval,
                "samples": int(self.wavelengths.size),
            },
            "xyz_integration": "colour.msds_to_XYZ method 'Integration', perfect reflector Y = 100",
            "lab_reference_white_XYZ": [float(v) for v in self.white_XYZ],
            "delta_e": "CIE 2000",
            "colour_science": _colour().__version__,
        }

    def spectra_to_XYZ(self, spectra: ArrayLike) -> NDArray[np.float64]:
        """XYZ (perfect reflector Y = 100) of reflectance spectra sampled on ``wavelengths``.

        Parameters
        ----------
        spectra : array_like, shape (..., N)

        Returns
        -------
        ndarray, shape (..., 3)
        """
        spectra = np.asarray(spectra, dtype=np.float64)
        if spectra.shape[-1] != self.wavelengths.size:
            raise ValueError(
                f"spectra must have {self.wavelengths.size} samples on the last axis "
                f"({self.shape[0]:g}-{self.shape[1]:g} nm every {self.shape[2]:g} nm), "
                f"got shape {spectra.shape}"
            )
        colour = _colour()
        return colour.msds_to_XYZ(
            spectra, self._cmfs, self._illuminant_sd, method="Integration", shape=self.colour_shape
        )

    def XYZ_to_RGB(self, XYZ: ArrayLike) -> NDArray[np.float64]:
        """Working-space linear RGB (reflectance scale, white = 1) of XYZ (Y = 100)."""
        colour = _colour()
        return colour.XYZ_to_RGB(
            np.asarray(XYZ, np.float64) / 100.0,
            self._space,
            illuminant=self.white_xy,
            chromatic_adaptation_transform=CAT,
        )

    def RGB_to_XYZ(self, RGB: ArrayLike) -> NDArray[np.float64]:
        """XYZ (Y = 100, illuminant white) of working-space linear RGB (white = 1)."""
        colour = _colour()
        return 100.0 * colour.RGB_to_XYZ(
            np.asarray(RGB, np.float64), self._space, illuminant=self.white_xy, chromatic_adaptation_transform=CAT
        )

    def XYZ_to_Lab(self, XYZ: ArrayLike) -> NDArray[np.float64]:
        """CIELAB of XYZ (Y = 100) with the illuminant's white as reference white."""
        colour = _colour()
        return colour.XYZ_to_Lab(np.asarray(XYZ, np.float64) / 100.0, self.white_xy)

    @staticmethod
    def delta_E(Lab1: ArrayLike, Lab2: ArrayLike) -> NDArray[np.float64]:
        """CIEDE2000 colour difference."""
        return _colour().delta_E(Lab1, Lab2, method="CIE 2000")

    @staticmethod
    def chroma(Lab: ArrayLike) -> NDArray[np.float64]:
        """CIELAB chroma C*ab = sqrt(a*^2 + b*^2)."""
        return _colour().Lab_to_LCHab(Lab)[..., 1]


def working_space_name(name: str) -> str:
    """The ``WORKING_SPACES`` key a working-space name or alias stands for (case-insensitive)."""
    if not isinstance(name, str):
        raise TypeError(f"working_space must be a string, got {type(name).__name__}")
    key = name.strip().lower()
    key = WORKING_SPACE_ALIASES.get(key, key)
    if key not in WORKING_SPACES:
        raise ValueError(
            f"working_space must be one of {', '.join(WORKING_SPACES)} (or an alias such as "
            f"lin_ap1_scene, rec709); got {name!r}"
        )
    return key


def colorimetry(
    illuminant: str = DEFAULT_ILLUMINANT,
    working_space: str = DEFAULT_WORKING_SPACE,
    shape: tuple[float, float, float] = DEFAULT_SHAPE,
) -> Colorimetry:
    """The ``Colorimetry`` for an illuminant, a working space and a spectral shape (cached).

    Parameters
    ----------
    illuminant : str
        A name of ``colour.SDS_ILLUMINANTS`` ("D65" default, "A", "D50", "FL2", ...).
    working_space : str
        One of ``WORKING_SPACES`` ("lin_rec709" default, "acescg", ...) or an alias of
        ``WORKING_SPACE_ALIASES`` (case-insensitive).
    shape : (start, end, interval) in nm
        Spectral sampling (default 380-780 nm every 5 nm).

    Examples
    --------
    >>> c = colorimetry()
    >>> c.wavelengths.size, [round(float(v), 3) for v in c.white_XYZ]
    (81, [95.043, 100.0, 108.88])
    >>> [round(float(v), 6) for v in c.XYZ_to_RGB(c.white_XYZ)]   # white -> RGB (1, 1, 1)
    [1.0, 1.0, 1.0]
    """
    working_space = working_space_name(working_space)
    try:
        start, end, interval = (float(v) for v in shape)
    except (TypeError, ValueError):
        raise TypeError(f"shape must be (start, end, interval) in nm, got {shape!r}") from None
    if not (300.0 <= start < end <= 830.0 and 0.0 < interval <= end - start):
        raise ValueError(f"shape must satisfy 300 <= start < end <= 830 nm and 0 < interval, got {shape!r}")
    if not isinstance(illuminant, str):
        raise TypeError(f"illuminant must be a string, got {type(illuminant).__name__}")
    return _colorimetry(illuminant, working_space, (start, end, interval))


@lru_cache(maxsize=16)
def _colorimetry(illuminant, working_space, shape):
    colour = _colour()
    if illuminant not in colour.SDS_ILLUMINANTS:  # a CanonicalMapping: case-insensitive lookup
        raise ValueError(
            f"illuminant must be a name of colour.SDS_ILLUMINANTS (e.g. D65, D50, A, FL2, LED-B1); got {illuminant!r}"
        )
    illuminant = next(
        (k for k in colour.SDS_ILLUMINANTS.keys() if k.lower() == illuminant.lower()),
        colour.SDS_ILLUMINANTS[illuminant].name,
    )
    cshape = colour.SpectralShape(*shape)
    cmfs = colour.MSDS_CMFS[OBSERVER].copy().align(cshape)
    sd = colour.SDS_ILLUMINANTS[illuminant].copy().align(cshape)
    wavelengths = np.asarray(cshape.wavelengths, np.float64)
    white = colour.msds_to_XYZ(np.ones(wavelengths.size), cmfs, sd, method="Integration", shape=cshape)
    space = colour.RGB_COLOURSPACES[WORKING_SPACES[working_space]]
    return Colorimetry(
        illuminant,
        working_space,
        shape,
        wavelengths,
        np.asarray(white, np.float64),
        np.asarray(colour.XYZ_to_xy(white / 100.0), np.float64),
        cmfs,
        sd,
        space,
    )
