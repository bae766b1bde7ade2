"""Spectral versus RGB colour-shift validation of EON (colour-science does the colorimetry).

Importing this package is cheap: colour-science is imported only when a function of
``colorimetry``, ``recovery``, ``colorsets`` or ``validation`` runs.

Pipeline: reflectance spectrum -> EON directional albedo per wavelength
(``directional_albedo`` with the spectral samples as channels) -> XYZ under an illuminant
(CIE 1931 2 degree observer) -> working-space RGB (Bradford adaptation); RGB colours are
upsampled to spectra by a ``colour.recovery`` method (``recovery.RECOVERY_METHODS``).
"""

from .colorimetry import DEFAULT_ILLUMINANT, DEFAULT_WORKING_SPACE, WORKING_SPACES, Colorimetry, colorimetry
from .colorsets import ColourSet, checker, from_materials, from_rgb, from_spectra, from_spectra_csv
from .recovery import RECOVERY_METHODS, rgb_to_spectra
from .validation import ColourShift, colour_shift

__all__ = [
    "WORKING_SPACES",
    "DEFAULT_WORKING_SPACE",
    "DEFAULT_ILLUMINANT",
    "Colorimetry",
    "colorimetry",
    "RECOVERY_METHODS",
    "rgb_to_spectra",
    "ColourSet",
    "checker",
    "from_rgb",
    "from_spectra",
    "from_spectra_csv",
    "from_materials",
    "ColourShift",
    "colour_shift",
]
