"""Texture lookups at one uv with OpenImageIO's TextureSystem (UsdUVTexture, ND_image_*,
ND_tiledimage_*).

uv follows USD and MaterialX: (0, 0) is the lower-left corner of the image, v points up.
OpenImageIO's t axis points down, so the lookup is at (s, t) = (u, 1 - v).  Filtering is
bilinear at the finest level (zero footprint: one surface point, not a pixel's area).

Wrap modes (USD ``wrapS/wrapT`` and MaterialX ``uaddressmode/vaddressmode``):
repeat / periodic, mirror, clamp, black; MaterialX "constant" returns the node's ``default``
outside [0, 1] (handled by the caller through ``outside_unit``), USD "useMetadata" uses the
file's own wrap metadata (OpenImageIO's Wrap.Default).
"""
import functools
import os

import numpy as np

_WRAPS = {
    "repeat": "Periodic", "periodic": "Periodic", "mirror": "Mirror", "clamp": "Clamp",
    "black": "Black", "constant": "Black", "usemetadata": "Default", "": "Periodic",
}


class TextureError(OSError):
    """A texture file is missing or unreadable (callers fall back and warn)."""


def wrap_name(mode):
    """Validate a wrap / address mode name; returns its lower-case form."""
    if not isinstance(mode, str) or mode.lower() not in _WRAPS:
        raise ValueError(f"wrap mode {mode!r} is not known; expected one of "
                         "repeat, periodic, mirror, clamp, black, constant, useMetadata")
    return mode.lower()


#: Pixels an untiled texture may declare (8192 x 8192): TextureSystem reads an untiled file
#: whole, so a small PNG that declares 30000 x 30000 would cost gigabytes for one texel.
#: Tiled files (OpenEXR, tiled TIFF) are read a tile at a time and have no such limit.
MAX_UNTILED_PIXELS = 8192 * 8192
#: Memory OpenImageIO's texture cache may hold, MB.
CACHE_MB = 512


@functools.lru_cache(maxsize=1)
def _system():
    import OpenImageIO as oiio

    ts = oiio.TextureSystem(shared=False)
    ts.attribute("max_memory_MB", float(CACHE_MB))
    return ts


@functools.lru_cache(maxsize=256)
def file_info(path, mtime):
    """(channels, bits per channel, OpenImageIO colour space) of an image file."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise TextureError(f"texture {path!r} cannot be read: {oiio.geterror() or 'unknown format'}")
    try:
        spec = inp.spec()
        if spec.tile_width == 0 and spec.width * spec.height > MAX_UNTILED_PIXELS:
            raise TextureError(f"texture {path!r} declares {spec.width} x {spec.height} pixels, untiled: "
                               f"above the limit of {MAX_UNTILED_PIXELS} pixels read whole (tile it, e.g. "
                               f"with maketx)")
        return spec.nchannels, spec.format.size() * 8, spec.get_string_attribute("oiio:ColorSpace", "")
    finally:
        inp.close()


def info(path):
    """Channels, bits and colour space metadata of ``path`` (TextureError if unreadable)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise TextureError(f"texture file {path!r} does not exist")
    return file_info(path, os.stat(path).st_mtime_ns)


def sample(path, uv, wrap_s="periodic", wrap_t="periodic"):
    """The texel value of ``path`` at ``uv`` (bilinear), one value per channel of the file.

    Parameters
    ----------
    path : str or Path
    uv : (u, v) floats (v up)
    wrap_s, wrap_t : str
        Wrap modes (see module docstring).

    Returns
    -------
    ndarray (nchannels,) float64

    Raises
    ------
    TextureError
        The file is missing or unreadable.
    """
    import OpenImageIO as oiio

    path = os.fspath(path)
    nch, _, _ = info(path)
    u, v = (float(x) for x in uv)
    if not (np.isfinite(u) and np.isfinite(v)):
        raise ValueError(f"uv must be finite, got {uv!r}")
    opt = oiio.TextureOpt()
    opt.swrap = getattr(oiio.Wrap, _WRAPS[wrap_name(wrap_s)])
    opt.twrap = getattr(oiio.Wrap, _WRAPS[wrap_name(wrap_t)])
    opt.interpmode = oiio.InterpMode.Bilinear
    ts = _system()
    out = ts.texture(path, opt, u, 1.0 - v, 0.0, 0.0, 0.0, 0.0, nch)
    err = ts.geterror()
    if err:
        raise TextureError(f"texture {path!r}: {err.strip().splitlines()[0]}")
    return np.asarray(out, dtype=np.float64)


def outside_unit(uv):
    """True if uv lies outside [0, 1]^2 (MaterialX "constant" address mode uses ``default``)."""
    return bool(np.any((np.asarray(uv, dtype=np.float64) < 0.0) | (np.asarray(uv, dtype=np.float64) > 1.0)))


__all__ = ["TextureError", "sample", "info", "wrap_name", "outside_unit"]
