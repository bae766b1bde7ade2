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
next to the package) and removed when the interpreter exits.  The folder holds a stamp file
naming its owner process; a folder left behind by a process that was killed (SIGKILL: no exit
handler runs) is recognised by its name and stamp, its owner no longer running, and removed
the next time a folder is made (:func:`remove_leftovers`).

A texture that cannot be decoded (a corrupt PNG) gives the same TextureError at every lookup
in the process -- the first one's message, kept per file -- so every material that uses it
falls back the same way; what the image libraries print on stderr (``libpng error: ...``) is
captured, their message being in the error.
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

from ._capture import captured_stderr

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

    with captured_stderr([]):
        inp = oiio.ImageInput.open(path)
    if inp is None:
        raise TextureError(f"texture {path!r} cannot be read: {_first_line(oiio.geterror()) or 'unknown format'}")
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
#: Name prefix of the private folders, and the stamp file in each ("PID START": the owner's
#: process id and, on Linux, its start time in clock ticks, which tells a reused pid apart).
PREFIX = "openpbr_diffuse_packaged_"
STAMP = "owner"


def _start_time(pid: int) -> str:
    """The start time of process ``pid`` (Linux /proc, clock ticks since boot; "" if unknown)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            stat = f.read()
        return stat[stat.rindex(b")") + 2 :].split()[19].decode()
    except (OSError, ValueError, IndexError):
        return ""


def _alive(pid: int, start: str) -> bool:
    """Whether the process that wrote a stamp ``PID START`` still runs."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: running
        pass
    now = _start_time(pid)
    return not (start and now and now != start)


def remove_leftovers(folder: str | None = None) -> list[str]:
    """Remove private folders that processes of this tool left in ``folder`` (default: the
    temporary folder) when they were killed: a folder is removed only if it is a real folder
    (not a symbolic link) of this user named ``PREFIX*`` whose stamp file names a process that
    no longer runs.  Nothing is followed through a symbolic link.  Returns the folders removed.

    Examples
    --------
    >>> import os, tempfile
    >>> base = tempfile.mkdtemp()
    >>> left = os.path.join(base, PREFIX + "x")
    >>> os.mkdir(left)
    >>> with open(os.path.join(left, STAMP), "w") as f:
    ...     _ = f.write("999999999 1")          # no such process
    >>> mine = tempfile.mkdtemp(prefix=PREFIX, dir=base)
    >>> _write_stamp(mine)                      # this process: kept
    >>> [os.path.basename(p) for p in remove_leftovers(base)], sorted(os.listdir(base)) == [os.path.basename(mine)]
    (['openpbr_diffuse_packaged_x'], True)
    """
    import stat as st

    base = folder or tempfile.gettempdir()
    if not getattr(shutil.rmtree, "avoids_symlink_attacks", False):
        return []  # removal here could be raced into following a link: leave them
    removed = []
    try:
        entries = list(os.scandir(base))
    except OSError:
        return []
    for entry in entries:
        if not entry.name.startswith(PREFIX):
            continue
        try:
            info = entry.stat(follow_symlinks=False)
            if not st.S_ISDIR(info.st_mode) or info.st_uid != os.getuid():
                continue
            fd = os.open(os.path.join(entry.path, STAMP), os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
            with os.fdopen(fd, "rb") as f:
                words = f.read(64).split()
            pid, start = int(words[0]), (words[1].decode() if len(words) > 1 else "")
        except (OSError, ValueError, IndexError):
            continue  # not a folder with a stamp of ours: left alone
        if pid == os.getpid() or _alive(pid, start):
            continue
        shutil.rmtree(entry.path, ignore_errors=True)
        if not os.path.lexists(entry.path):
            removed.append(entry.path)
    return removed


def _write_stamp(folder: str) -> None:
    fd = os.open(os.path.join(folder, STAMP), os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(f"{os.getpid()} {_start_time(os.getpid())}\n")


def _private_dir() -> str:
    """A temporary folder of this process (made on first use, removed at exit; leftovers of
    killed processes removed when it is made)."""
    if not _PRIVATE or _PRIVATE[1] != os.getpid():  # a forked child makes (and removes) its own
        remove_leftovers()
        d = tempfile.mkdtemp(prefix=PREFIX)
        _write_stamp(d)
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
    st = os.stat(path)
    key = (path, st.st_mtime_ns, st.st_size)
    if key in _BROKEN:
        raise TextureError(f"texture {name!r}: {_BROKEN[key]}")
    with captured_stderr([]):  # libpng prints its errors on fd 2 too; OpenImageIO's error has them
        out = ts.texture(path, opt, u, 1.0 - v, 0.0, 0.0, 0.0, 0.0, nch)
        err = ts.geterror()
    if err:
        # the cache now holds a broken file and would answer the next lookups with no error
        # and undefined texels: every later lookup gets this error instead
        _BROKEN[key] = _first_line(err).replace(path, name)
        raise TextureError(f"texture {name!r}: {_BROKEN[key]}")
    return np.asarray(out, dtype=np.float64)


#: Texture files that failed to decode in this process: (path, mtime, size) -> the error.
_BROKEN: dict[tuple, str] = {}


def _first_line(text: str) -> str:
    text = (text or "").strip()
    return text.splitlines()[0] if text else ""


def outside_unit(uv: ArrayLike) -> bool:
    """True if uv lies outside [0, 1]^2 (MaterialX "constant" address mode uses ``default``)."""
    return bool(np.any((np.asarray(uv, dtype=np.float64) < 0.0) | (np.asarray(uv, dtype=np.float64) > 1.0)))


__all__ = [
    "TextureError",
    "sample",
    "info",
    "wrap_name",
    "outside_unit",
    "local_file",
    "is_packaged",
    "display_name",
    "remove_leftovers",
]
