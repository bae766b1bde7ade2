"""Colour sets for the validation: measured ColorChecker spectra, user RGB, material files.

A ``ColourSet`` holds, per colour, a reflectance spectrum on the pipeline's wavelengths,
its working-space RGB (``rho_rgb``) and where both came from:

- ``checker(cm)``: the 24 measured spectra of colour-science's
  ``SDS_COLOURCHECKERS['BabelColor Average']`` (380-730 nm / 10 nm, aligned to the pipeline's
  shape by colour-science: Sprague interpolation, constant extrapolation above 730 nm);
  ``rho_rgb`` is the colour of the measured spectrum;
- ``from_rgb(rgb, cm, method)``: user colours (working-space linear RGB in [0, 1]),
  upsampled by ``recovery.rgb_to_spectra``; ``rho_rgb`` is the user's RGB;
- ``from_spectra_csv(path, cm)``: measured spectra in a CSV file (first column the
  wavelength in nm, one column per named spectrum, reflectance in [0, 1]);
- ``from_materials(paths, cm, method)``: the diffuse colour of each supported material of
  USD / MaterialX files, read by ``openpbr_diffuse.readers.load_materials`` (colours in
  ACEScg, converted to the working space), upsampled.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..library.colours import DIFFUSE_COLOR_INPUTS, DIFFUSE_ROUGHNESS_INPUTS  # noqa: F401 -- part of this API
from .colorimetry import _colour
from .recovery import check_rgb, resolve_method, rgb_to_spectra

if TYPE_CHECKING:
    from .colorimetry import Colorimetry

CHECKER = "BabelColor Average"
MATERIAL_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz", ".mtlx")
#: fewest wavelength rows of a spectra CSV (colour-science's Sprague interpolation needs 6).
MIN_CSV_SAMPLES = 6


@dataclass
class ColourSet:
    """Named reflectance spectra with their working-space RGB.

    Attributes
    ----------
    names : list of str
    spectra : ndarray, shape (P, N), reflectance in [0, 1] on the pipeline's wavelengths
    rho_rgb : ndarray, shape (P, 3), working-space linear RGB of each colour
    source : list of str
        "measured: ..." or "rgb (upsampled: METHOD)" or "material FILE:PATH (upsampled: METHOD)".
    roundtrip_delta_e : ndarray, shape (P,)
        CIEDE2000 between ``rho_rgb`` and the colour of the spectrum; NaN for measured
        spectra (their ``rho_rgb`` is computed from the spectrum: no round trip).
    extra : list of dict
        Per colour, fields added to the output rows (e.g. a material's own roughness).
    """

    names: list
    spectra: np.ndarray
    rho_rgb: np.ndarray
    source: list
    roundtrip_delta_e: np.ndarray
    extra: list = field(default_factory=list)

    def __post_init__(self):
        if not self.extra:
            self.extra = [{} for _ in self.names]

    def __len__(self):
        return len(self.names)

    @staticmethod
    def concat(sets: Iterable[ColourSet]) -> ColourSet:
        sets = [s for s in sets if len(s)]
        if not sets:
            raise ValueError("colors: no colours to evaluate")
        return ColourSet(
            sum((s.names for s in sets), []),
            np.concatenate([s.spectra for s in sets]),
            np.concatenate([s.rho_rgb for s in sets]),
            sum((s.source for s in sets), []),
            np.concatenate([s.roundtrip_delta_e for s in sets]),
            sum((s.extra for s in sets), []),
        )


def _measured(names, spectra, cm, source):
    spectra = np.asarray(spectra, np.float64)
    bad = ~np.isfinite(spectra) | (spectra < 0.0) | (spectra > 1.0)
    if np.any(bad):
        i = int(np.argmax(bad.any(axis=1)))
        raise ValueError(
            f"spectrum {names[i]!r} ({source}) must be a reflectance in [0, 1] on {cm.shape[0]:g}-{cm.shape[1]:g} nm"
        )
    rgb = cm.XYZ_to_RGB(cm.spectra_to_XYZ(spectra))
    return ColourSet(list(names), spectra, rgb, [f"measured: {source}"] * len(names), np.full(len(names), np.nan))


def from_spectra(
    spectra: ArrayLike, cm: Colorimetry, names: Sequence[str] | None = None, source: str = "spectra"
) -> ColourSet:
    """Reflectance spectra already sampled on ``cm.wavelengths`` (array (P, N) in [0, 1]).

    Examples
    --------
    >>> from openpbr_diffuse.spectral.colorimetry import colorimetry
    >>> cm = colorimetry()
    >>> cs = from_spectra([[0.5] * 81], cm)
    >>> [round(float(v), 6) for v in cs.rho_rgb[0]]
    [0.5, 0.5, 0.5]
    """
    spectra = np.atleast_2d(np.asarray(spectra, np.float64))
    if spectra.ndim != 2 or spectra.shape[1] != cm.wavelengths.size:
        raise ValueError(
            f"spectra must have shape (P, {cm.wavelengths.size}) on {cm.shape[0]:g}-{cm.shape[1]:g} nm "
            f"every {cm.shape[2]:g} nm; got {spectra.shape}"
        )
    names = [f"spectrum {i}" for i in range(len(spectra))] if names is None else list(names)
    if len(names) != len(spectra):
        raise ValueError(f"names must have one entry per spectrum ({len(spectra)}), got {len(names)}")
    return _measured(names, spectra, cm, source)


def checker(cm: Colorimetry) -> ColourSet:
    """The 24 measured ColorChecker spectra ('BabelColor Average' of colour-science).

    Examples
    --------
    >>> from openpbr_diffuse.spectral.colorimetry import colorimetry
    >>> cs = checker(colorimetry())
    >>> len(cs), cs.names[0], cs.spectra.shape
    (24, 'dark skin', (24, 81))
    """
    colour = _colour()
    sds = colour.SDS_COLOURCHECKERS[CHECKER]
    names = list(sds)
    spectra = np.array([sds[n].copy().align(cm.colour_shape).values for n in names])
    return _measured(names, spectra, cm, f"colour.SDS_COLOURCHECKERS['{CHECKER}']")


def from_rgb(
    rgb: ArrayLike, cm: Colorimetry, method: str = "auto", names: Sequence[str] | None = None, source: str = "rgb"
) -> ColourSet:
    """User colours (working-space linear RGB in [0, 1]) upsampled with ``method``."""
    rgb = check_rgb("colors", np.atleast_2d(rgb))
    name = resolve_method(method, cm)
    spectra, de = rgb_to_spectra(rgb, cm, name)
    if names is None:
        names = [",".join(f"{v:g}" for v in c) for c in rgb]
    return ColourSet(list(names), spectra, rgb, [f"{source} (upsampled: {name})"] * len(rgb), de)


def from_spectra_csv(path: str | os.PathLike[str], cm: Colorimetry) -> ColourSet:
    """Measured reflectance spectra from a CSV file: wavelength (nm), then one column per spectrum.

    The first row names the columns; lines starting with ``#`` are comments.  Each spectrum
    is aligned to the pipeline's shape by colour-science (interpolation; constant
    extrapolation outside the measured range).
    """
    colour = _colour()
    path = Path(path)
    with open(path, encoding="utf-8") as f:
        lines = [ln for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
    if len(lines) < 1 + MIN_CSV_SAMPLES:
        raise ValueError(f"{path}: a spectra CSV needs a header and at least {MIN_CSV_SAMPLES} wavelength rows")
    header = [h.strip() for h in lines[0].split(",")]
    cells = [ln.split(",") for ln in lines[1:]]
    if len(header) < 2 or any(len(c) != len(header) for c in cells):
        raise ValueError(f"{path}: every row must have the header's {len(header)} columns (wavelength + spectra)")
    try:
        data = np.array([[float(v) for v in c] for c in cells])
    except ValueError:
        raise ValueError(f"{path}: every row after the header must be numbers") from None
    wl = data[:, 0]
    if not (np.all(np.diff(wl) > 0) and wl[0] >= 300 and wl[-1] <= 830):
        raise ValueError(f"{path}: wavelengths must increase, within 300-830 nm")
    values = data[:, 1:]
    if not np.all(np.isfinite(values)) or np.any((values < 0) | (values > 1)):
        raise ValueError(f"{path}: reflectances must lie in [0, 1]")
    # interpolation (Sprague for uniform data) may overshoot [0, 1] slightly near 0 or 1: clipped
    spectra = [
        np.clip(
            colour.SpectralDistribution(dict(zip(wl, values[:, j])), name=header[j + 1]).align(cm.colour_shape).values,
            0.0,
            1.0,
        )
        for j in range(values.shape[1])
    ]
    return _measured(header[1:], spectra, cm, str(path))


def from_materials(
    paths: Iterable[str | os.PathLike[str]], cm: Colorimetry, method: str = "auto"
) -> tuple[ColourSet, list[str]]:
    """The diffuse colours of the supported materials of USD / MaterialX files.

    ``openpbr_diffuse.readers.load_materials`` resolves every colour into its working space,
    ACEScg (``readers.WORKING_SPACE``); it is converted here to ``cm``'s working space
    (Bradford), clipped to [0, 1] (with a warning) and upsampled with ``method``.  Unsupported
    materials and ones without a diffuse colour are skipped with a warning.  The validation
    evaluates EON whatever the material's own diffuse model (``material_diffuse_model`` in
    the rows says which it is).

    Returns
    -------
    (ColourSet, warnings) : warnings is a list of str.
    """
    try:
        from ..readers import load_materials
    except ImportError as exc:
        raise ValueError(f"reading material files needs openpbr_diffuse.readers ({exc})") from None
    from ..library.colours import colour_record

    records = [colour_record(m) for path in paths for m in load_materials(path)]
    return from_colour_records(records, cm, method)


def from_colour_records(records: Sequence[dict], cm: Colorimetry, method: str = "auto") -> tuple[ColourSet, list[str]]:
    """:func:`from_materials` of the materials' colour records
    (:func:`openpbr_diffuse.library.colours.colour_record`, as the library cache keeps them).

    Examples
    --------
    >>> from openpbr_diffuse.library.colours import colour_record
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials
    >>> from openpbr_diffuse.spectral.colorimetry import colorimetry
    >>> cs, warnings = from_colour_records(
    ...     [colour_record(m) for m in load_materials(BUNDLED_MATERIALS / "clay_rough.mtlx")], colorimetry()
    ... )
    >>> cs.names, cs.extra[0]["material_diffuse_roughness"], warnings
    (['clay_rough'], 1.0, [])
    """
    from .. import readers

    source_space = getattr(readers, "WORKING_SPACE", "acescg")
    # the colours of every usable record are converted at once; each record's warnings keep
    # their place (its reader warnings, then why it is skipped or clipped)
    kept, texts = [], []
    for r in records:
        where = f"{r['file']}:{r['path']}"
        texts.append([f"{where}: {w}" for w in r["warnings"]])
        rgb = None if r["rgb"] is None else np.array([float(v) for v in r["rgb"]], np.float64)
        if not r["supported"] or rgb is None or rgb.size != 3:
            why = f"unsupported shader {r['shader']}" if not r["supported"] else "no diffuse colour"
            texts[-1].append(f"{where}: skipped ({why})")
            continue
        kept.append((len(texts) - 1, r, where, rgb))
    converted = _to_working_space(np.array([k[3] for k in kept]), source_space, cm) if kept else []
    names, rgbs, sources, extra = [], [], [], []
    for (at, r, where, _), rgb in zip(kept, converted):
        clipped = np.clip(rgb, 0.0, 1.0)
        if np.any(abs(clipped - rgb) > 1e-9):
            texts[at].append(f"{where}: {r['key']} {np.round(rgb, 6).tolist()} ({cm.working_space}) clipped to [0, 1]")
        names.append(r["name"])
        rgbs.append(clipped)
        sources.append(f"material {where} {r['key']}")
        extra.append(
            {
                "material_file": r["file"],
                "material_path": r["path"],
                "material_shader": r["shader"],
                "material_diffuse_model": r["diffuse_model"],
                "material_diffuse_roughness": None if r["roughness"] is None else float(r["roughness"]),
            }
        )
    warnings = [t for ts in texts for t in ts]
    if not names:
        return ColourSet([], np.zeros((0, cm.wavelengths.size)), np.zeros((0, 3)), [], np.zeros(0)), warnings
    name = resolve_method(method, cm)
    cs = from_rgb(np.array(rgbs), cm, name, names=names, source="material")
    cs.source = [f"{s} ({source_space} -> {cm.working_space}; upsampled: {name})" for s in sources]
    cs.extra = extra
    return cs, warnings


def _to_working_space(rgb, source_space, cm):
    """A colour in the readers' working space (MaterialX name) as ``cm``'s working-space RGB."""
    from .colorimetry import WORKING_SPACES

    if source_space == cm.working_space:
        return rgb
    colour = _colour()
    names = {"acescg": "ACEScg", **WORKING_SPACES}
    if source_space not in names:
        raise ValueError(f"material colours in {source_space!r}: no conversion to {cm.working_space}")
    XYZ = 100.0 * colour.RGB_to_XYZ(
        rgb,
        colour.RGB_COLOURSPACES[names[source_space]],
        illuminant=cm.white_xy,
        chromatic_adaptation_transform="Bradford",
    )
    return cm.XYZ_to_RGB(XYZ)
