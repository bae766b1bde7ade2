"""Texture lookups at one uv with OpenImageIO's TextureSystem (UsdUVTexture, ND_image_*,
ND_tiledimage_*).

uv follows USD and MaterialX: (0, 0) is the lower-left corner of the image, v points up.
OpenImageIO's t axis points down, so the lookup is at (s, t) = (u, 1 - v).  Filtering is
bilinear at the finest level (zero footprint: one surface point, not a pixel's area).

Wrap modes (USD ``wrapS/wrapT`` and MaterialX ``uaddressmode/vaddressmode``):
repeat / periodic, mirror, clamp, black; MaterialX "constant" returns the node's ``default``
outside [0, 1] (handled by the caller through ``outside_unit``), USD "useMetadata" uses the
file's own wrap metadata (OpenImageIO's Wrap.Default).

Textures inside a USD package (``scene.usdz[textures/a.png]``, as usd-core's asset resolver
resolves them) are read through that resolver (``Ar.GetResolver().OpenAsset``), never through
the file system.  OpenImageIO's Python bindings have no IOProxy (no reading from memory), so
the member's bytes are written once to a private temporary folder this module creates (never
next to the package) and removed when the interpreter exits.
"""

from __future__ import annotations

import atexit
import functools
import os
import shutil
import tempfile
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

_WRAPS = {
    "repeat": "Periodic",
    "periodic": "Periodic",
    "mirror": "Mirror",
    "clamp": "Clamp",
    "black": "Black",
    "constant": "Black",
    "usemetadata": "Default",
    "": "Periodic",
}


class TextureError(OSError):
    """A texture file is missing or unreadable (callers fall back and warn)."""


def wrap_name(mode: str) -> str:
    """Validate a wrap / address mode name; returns its lower-case form."""
    if not isinstance(mode, str) or mode.lower() not in _WRAPS:
        raise ValueError(
            f"wrap mode {mode!r} is not known; expected one of "
            "repeat, periodic, mirror, clamp, black, constant, useMetadata"
        )
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
            raise TextureError(
                f"texture {path!r} declares {spec.width} x {spec.height} pixels, untiled: "
                f"above the limit of {MAX_UNTILED_PIXELS} pixels read whole (tile it, e.g. "
                f"with maketx)"
            )
        return spec.nchannels, spec.format.size() * 8, spec.get_string_attribute("oiio:ColorSpace", "")
    finally:
        inp.close()


def is_packaged(path: str) -> bool:
    """Whether ``path`` names a member of a USD package (``pkg.usdz[member]``).

    Examples
    --------
    >>> is_packaged("/a/b.usdz[textures/c.png]"), is_packaged("/a/c.png")
    (True, False)
    """
    return path.endswith("]") and "[" in path


def display_name(path: str) -> str:
    """The file name of a texture path, of the innermost member for a packaged one.

    Examples
    --------
    >>> display_name("/a/b.usdz[textures/c.png]"), display_name("/a/c.png")
    ('c.png', 'c.png')
    """
    if is_packaged(path):
        path = path[path.rindex("[") + 1 : -1]
    return os.path.basename(path)


_PRIVATE: list = []  # [folder, pid of the process that made it]


def _private_dir() -> str:
    """A temporary folder of this process (made on first use, removed at exit)."""
    if not _PRIVATE or _PRIVATE[1] != os.getpid():  # a forked child makes (and removes) its own
        d = tempfile.mkdtemp(prefix="openpbr_diffuse_packaged_")
        atexit.register(_remove, d, os.getpid())
        _PRIVATE[:] = [d, os.getpid()]
        _member_file.cache_clear()
    return _PRIVATE[0]


def _remove(folder: str, pid: int) -> None:
    """Remove the private folder, only in the process that made it."""
    if os.getpid() == pid:
        shutil.rmtree(folder, ignore_errors=True)


def _package_stamp(path: str) -> int:
    """Modification time (ns) of the outermost package file of a packaged path."""
    from pxr import Ar

    outer, _ = Ar.SplitPackageRelativePathOuter(path)
    if not os.path.isfile(outer):
        raise TextureError(f"texture {path!r}: its package {outer!r} does not exist")
    return os.stat(outer).st_mtime_ns


@functools.lru_cache(maxsize=256)
def _member_file(path: str, stamp: int) -> str:
    """A private copy of the package member ``path`` read through usd-core's asset resolver."""
    from pxr import Ar

    asset = Ar.GetResolver().OpenAsset(Ar.ResolvedPath(path))
    if asset is None:
        raise TextureError(f"texture {path!r} is not in its package")
    data = asset.GetBuffer()
    fd, tmp = tempfile.mkstemp(suffix=os.path.splitext(display_name(path))[1], dir=_private_dir())
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    return tmp


def local_file(path: str) -> str:
    """A file OpenImageIO can open for ``path``: itself, or for a packaged member a private
    copy of its bytes (TextureError if missing).

    Examples
    --------
    >>> local_file("/no/such/texture.png")
    Traceback (most recent call last):
    ...
    openpbr_diffuse.readers.textures.TextureError: texture file '/no/such/texture.png' does not exist
    """
    path = os.fspath(path)
    if is_packaged(path):
        return _member_file(path, _package_stamp(path))
    if not os.path.isfile(path):
        raise TextureError(f"texture file {path!r} does not exist")
    return path


def info(path: str) -> tuple[int, int, str]:
    """Channels, bits and colour space metadata of ``path`` (TextureError if unreadable)."""
    name = os.fspath(path)
    local = local_file(name)
    try:
        return file_info(local, os.stat(local).st_mtime_ns)
    except TextureError as exc:  # name the texture as the file names it, not the private copy
        raise TextureError(str(exc).replace(local, name)) from None


def sample(path: str, uv: Iterable[float], wrap_s: str = "periodic", wrap_t: str = "periodic") -> NDArray[np.float64]:
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

    name = os.fspath(path)
    nch, _, _ = info(name)
    path = local_file(name)
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
        raise TextureError(f"texture {name!r}: {err.strip().splitlines()[0].replace(path, name)}")
    return np.asarray(out, dtype=np.float64)


def outside_unit(uv: ArrayLike) -> bool:
    """True if uv lies outside [0, 1]^2 (MaterialX "constant" address mode uses ``default``)."""
    return bool(np.any((np.asarray(uv, dtype=np.float64) < 0.0) | (np.asarray(uv, dtype=np.float64) > 1.0)))


__all__ = ["TextureError", "sample", "info", "wrap_name", "outside_unit", "local_file", "is_packaged", "display_name"]
