"""Reading a rendered chart image and measuring its tiles.

Images are read with OpenImageIO (EXR, HDR, TIFF, PNG, JPEG, ...).  Float images are
taken as linear.  Integer images (8/16 bit) are decoded by their transfer: sRGB unless the
file says it is linear (``oiio:ColorSpace`` naming a linear space); the quantisation step
is kept so that a tile's tolerance can include it.

A tile's measurement is the mean of its interior pixels -- the rectangle shrunk by
:data:`MARGIN` of its side on every edge, so the anti-aliased edges are left out -- and
the standard error of that mean (sample standard deviation / sqrt(n)).

Example
-------
>>> import numpy as np
>>> img = np.zeros((32, 32, 3), np.float32); img[4:24, 4:24] = 0.5
>>> m = tile_stats(img, [{"rect": [4, 4, 24, 24]}])
>>> m.mean[0].tolist(), int(m.n[0])
([0.5, 0.5, 0.5], 196)
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

#: The share of a tile's side left out on each edge.
MARGIN = 0.15
#: Largest image read (pixels): a 16k x 16k image.
MAX_PIXELS = 16384 * 16384
_LINEAR_NAMES = ("linear", "lin_", "scene_linear", "acescg", "aces2065", "raw")


@dataclass
class ChartImage:
    """A chart image as linear RGB (h, w, 3) float32, with how it was decoded."""

    pixels: np.ndarray
    encoding: str  # "linear" or "sRGB"
    bits: int  # 0 for float data, else the integer bits per channel
    path: str = ""


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer decoded (IEC 61966-2-1).

    >>> round(float(srgb_to_linear(np.array(0.5))), 6)
    0.214041
    """
    from ..conformance.deviations import srgb_decode

    return srgb_decode(np.asarray(x, np.float64))


def _srgb_slope(x):
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.04045, 1.0 / 12.92, 2.4 / 1.055 * ((x + 0.055) / 1.055) ** 1.4)


def read_image(path: str | os.PathLike[str]) -> ChartImage:
    """Read an image file as linear RGB (see the module docstring); never modifies it.

    Raises ``ValueError`` naming ``--image`` and the file for anything unreadable.

    >>> read_image("/nonexistent.exr")
    Traceback (most recent call last):
    ...
    ValueError: --image /nonexistent.exr: no such file
    """
    import OpenImageIO as oiio

    text = os.fspath(path)
    if not os.path.isfile(text):
        raise ValueError(f"--image {text}: no such file")
    inp = oiio.ImageInput.open(text)
    if inp is None:
        raise ValueError(f"--image {text}: not an image OpenImageIO can read ({oiio.geterror().strip()})")
    try:
        spec = inp.spec()
        if spec.width * spec.height > MAX_PIXELS:
            raise ValueError(f"--image {text}: {spec.width}x{spec.height} is larger than a 16k image")
        data = inp.read_image(0, 0, 0, min(spec.nchannels, 3), oiio.FLOAT)
    finally:
        inp.close()
    if data is None or not hasattr(data, "shape"):
        raise ValueError(f"--image {text}: could not read the pixels")
    data = np.asarray(data, np.float32).reshape(spec.height, spec.width, -1)
    if data.shape[2] == 1:
        data = np.repeat(data, 3, axis=2)
    elif data.shape[2] == 2:
        raise ValueError(f"--image {text}: two channels (grey + alpha?): expected RGB")
    fmt = str(spec.format)
    floating = fmt in ("half", "float", "double")
    colour = str(spec.getattribute("oiio:ColorSpace") or "").lower()
    if floating:
        return ChartImage(data, "linear", 0, text)
    bits = int(spec.getattribute("oiio:BitsPerSample") or {"uint8": 8, "uint16": 16}.get(fmt, 8))
    if any(colour.startswith(n) or n in colour for n in _LINEAR_NAMES) and "srgb" not in colour:
        return ChartImage(data, "linear", bits, text)
    return ChartImage(srgb_to_linear(data).astype(np.float32), "sRGB", bits, text)


@dataclass
class TileStats:
    """Per tile: interior ``mean`` (n, 3), ``stderr`` (n, 3), pixel count ``n`` (n,)."""

    mean: np.ndarray
    stderr: np.ndarray
    n: np.ndarray


def interior(rect: list[int], margin: float = MARGIN) -> tuple[int, int, int, int]:
    """The rectangle shrunk by ``margin`` of its side on each edge (at least one pixel).

    >>> interior([12, 12, 52, 52])
    (18, 18, 46, 46)
    """
    x0, y0, x1, y1 = rect
    mx = max(1, math.ceil(margin * (x1 - x0)))
    my = max(1, math.ceil(margin * (y1 - y0)))
    if x1 - x0 - 2 * mx < 1 or y1 - y0 - 2 * my < 1:
        mx, my = 0, 0
    return x0 + mx, y0 + my, x1 - mx, y1 - my


def tile_stats(pixels: np.ndarray, tiles: list[dict], margin: float = MARGIN) -> TileStats:
    """Mean and standard error of every tile's interior pixels.

    >>> img = np.zeros((20, 20, 3)); img[:, :10] = 1.0
    >>> s = tile_stats(img, [{"rect": [0, 0, 20, 20]}], margin=0.0)
    >>> float(s.mean[0, 0]), int(s.n[0])      # one edge pixel is always left out
    (0.5, 324)
    """
    n_t = len(tiles)
    mean = np.zeros((n_t, 3))
    se = np.zeros((n_t, 3))
    count = np.zeros(n_t, int)
    for k, t in enumerate(tiles):
        x0, y0, x1, y1 = interior(t["rect"], margin)
        block = np.asarray(pixels[y0:y1, x0:x1], np.float64).reshape(-1, 3)
        count[k] = len(block)
        mean[k] = block.mean(axis=0)
        se[k] = block.std(axis=0, ddof=1) / math.sqrt(len(block)) if len(block) > 1 else 0.0
    return TileStats(mean, se, count)


def quantisation_step(image: ChartImage, linear_mean: np.ndarray) -> np.ndarray:
    """Half a code value of the file at each mean, in linear units (0 for float data).

    A flat tile quantised to integers is off by up to half a step, and averaging does
    not remove it: the grader adds it to the tile's tolerance.

    >>> im = ChartImage(np.zeros((1, 1, 3), np.float32), "linear", 8)
    >>> round(float(quantisation_step(im, np.array([0.5]))[0]), 6)
    0.001961
    """
    if image.bits == 0:
        return np.zeros_like(linear_mean)
    step = 1.0 / (2**image.bits - 1)
    if image.encoding == "linear":
        return np.full_like(linear_mean, 0.5 * step)
    from ..conformance.deviations import srgb_encode

    enc = srgb_encode(np.clip(linear_mean, 0.0, 1.0))
    return 0.5 * step * _srgb_slope(enc)


def write_image(
    path: str | os.PathLike[str], pixels: np.ndarray, *, option: str = "--expected-image", force: bool = False
) -> None:
    """Write linear RGB (h, w, 3) to an image file by its suffix (EXR: float32), by the
    rule of every output file (never replaces an existing file unless ``force``).

    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.exr"
    >>> write_image(p, np.full((2, 2, 3), 0.25, np.float32))
    >>> read_image(p).pixels[0, 0].tolist()
    [0.25, 0.25, 0.25]
    """
    import OpenImageIO as oiio

    from .._outfile import output_file

    px = np.ascontiguousarray(pixels, np.float32)
    with output_file(path, option=option, force=force) as tmp:
        spec = oiio.ImageSpec(px.shape[1], px.shape[0], 3, oiio.FLOAT)
        out = oiio.ImageOutput.create(str(tmp))
        if out is None or not out.open(str(tmp), spec):
            raise ValueError(f"{option} {os.fspath(path)}: cannot write this image format ({oiio.geterror().strip()})")
        try:
            if not out.write_image(px):
                raise ValueError(f"{option} {os.fspath(path)}: {out.geterror().strip()}")
        finally:
            out.close()


__all__ = [
    "ChartImage",
    "TileStats",
    "read_image",
    "write_image",
    "tile_stats",
    "interior",
    "quantisation_step",
    "srgb_to_linear",
]
