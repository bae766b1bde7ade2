"""Labelled swatch image of a colour-shift result, written with OpenImageIO.

One row per colour; per (roughness, mu) a group of four swatches side by side:
L = Lambert (``rho_rgb``), R = RGB-evaluated EON (``albedo_rgb``), S = spectral EON
(``albedo_spectral``), W = white then tint (``albedo_white_tint``).  Text is drawn with
``ImageBufAlgo.render_text`` (the fonts shipped in the OpenImageIO wheel).  Swatch values
are working-space linear RGB; for display formats (PNG, JPEG, TIFF, ...) OpenImageIO's
built-in OCIO configuration converts them to sRGB-encoded Rec.709 (values outside that gamut
clip); ``.exr`` keeps the linear working-space values (colour space in the metadata).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._outfile import output_file

if TYPE_CHECKING:
    from .validation import ColourShift

#: working space -> OpenImageIO (built-in OCIO config) colour-space name.
OIIO_SPACES = {
    "lin_rec709": "Linear Rec.709 (sRGB)",
    "acescg": "ACEScg",
    "lin_rec2020": "Linear Rec.2020",
    "lin_p3d65": "Linear P3-D65",
}
DISPLAY = "sRGB Encoded Rec.709 (sRGB)"
LINEAR_SUFFIXES = (".exr",)
SWATCH, GAP, LABEL_W, HEAD_H, FONT = 28, 10, 200, 46, 13
KINDS = (("L", "rho_rgb"), ("R", "albedo_rgb"), ("S", "albedo_spectral"), ("W", "albedo_white_tint"))


def swatch_array(result: ColourShift) -> tuple[NDArray[np.float32], list[tuple[int, int, str]]]:
    """The image as float32 (H, W, 3) working-space linear RGB plus the label positions."""
    P, K, M = result.delta_e_shift.shape
    group_w = 4 * SWATCH + GAP
    W = LABEL_W + K * M * group_w
    H = HEAD_H + P * (SWATCH + 4)
    img = np.full((H, W, 3), 0.05, np.float32)  # dark grey background
    labels = []
    for g, (k, m) in enumerate(np.ndindex(K, M)):
        x0 = LABEL_W + g * group_w
        labels.append((x0, 16, f"r={result.roughness[k]:g} mu={result.mu[m]:g}"))
        for j, (letter, _) in enumerate(KINDS):
            labels.append((x0 + j * SWATCH + SWATCH // 3, HEAD_H - 8, letter))
        for p in range(P):
            y0 = HEAD_H + p * (SWATCH + 4)
            for j, (_, name) in enumerate(KINDS):
                v = result.rho_rgb[p] if name == "rho_rgb" else getattr(result, name)[p, k, m]
                img[y0 : y0 + SWATCH, x0 + j * SWATCH : x0 + (j + 1) * SWATCH - 2] = v  # 2 px apart
    for p, name in enumerate(result.colours.names):
        labels.append((6, HEAD_H + p * (SWATCH + 4) + SWATCH // 2 + 5, name[:26]))
    return img, labels


def write_swatches(
    result: ColourShift,
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> Path:
    """Write the swatch image of ``result`` (a ``ColourShift``) to ``path`` (format by suffix).

    By the rule of every output file (:func:`openpbr_diffuse._outfile.output_file`): an
    existing file is replaced only with ``force`` (a regular file, never a symbolic link or
    one of ``inputs``), through a temporary sibling that keeps the suffix.  Returns the
    path.  Raises ``OutputFileError`` (a ``ValueError``) naming ``--image`` when the path may
    not be written, OSError if OpenImageIO cannot write it.
    """
    import OpenImageIO as oiio

    path = Path(path)
    img, labels = swatch_array(result)
    img = np.clip(img, 0.0, None)
    buf = oiio.ImageBuf(np.ascontiguousarray(img))
    space = OIIO_SPACES[result.colorimetry.working_space]
    linear = path.suffix.lower() in LINEAR_SUFFIXES
    if not linear:
        converted = oiio.ImageBufAlgo.colorconvert(buf, space, DISPLAY)
        if converted.has_error:
            raise OSError(f"--image: colour conversion {space} -> {DISPLAY} failed: {converted.geterror()}")
        buf = converted
    text = (1.0, 1.0, 1.0)
    for x, y, s in labels:
        oiio.ImageBufAlgo.render_text(buf, int(x), int(y), s, FONT, "", text)
    buf.specmod().attribute("oiio:ColorSpace", space if linear else DISPLAY)
    buf.specmod().attribute(
        "ImageDescription",
        "openpbr-diffuse colorshift: L Lambert, R RGB-evaluated EON, S spectral EON, W white then tint",
    )
    with output_file(path, option="--image", force=force, inputs=inputs) as tmp:
        if not buf.write(str(tmp), "half" if linear else "uint8"):
            why = (buf.geterror() or oiio.geterror()).replace(str(tmp), str(path))  # name the file asked for
            raise OSError(f"--image: cannot write {path}: {' '.join(why.split())}")
    return path
