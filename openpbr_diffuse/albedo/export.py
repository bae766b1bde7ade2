"""Albedo lookup textures for real-time engines: 32-bit float OpenEXR through OpenImageIO.

Two files per model, values from the reference tables (``tables.load_table``):

- ``<model>_albedo.exr``: N x N, texel (i, j) (column i, row j, row 0 first in the file) at
  the texel centres mu = (i + 0.5)/N and roughness = (j + 0.5)/N * roughness_max, so a GPU
  sampler reads E(mu, roughness) at uv = (mu, roughness / roughness_max) with bilinear
  filtering and clamp-to-edge addressing;
- ``<model>_average_albedo.exr``: N x 1, texel i at roughness = (i + 0.5)/N * roughness_max.

Channels (the same in both): R = E at rho = 1, G = e_g, B = e_h, with
E(rho) = rho e_g + m(rho) e_h (m = 0, rho^2, or EON's rho_ms(rho, <E_F>(r)) of Eq. 18), so a
chromatic albedo is exact from G and B.  The axis conventions and channel meaning are also
written into the files' metadata (``openpbr_diffuse:*`` attributes).
"""

import errno
import os
import sys
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._outfile import check_output_file, output_file
from .._version import __version__
from ..models.registry import INFO, MIX_LINEAR, MIX_RHO2, MIX_RHO_MS, model_info
from ..models.tables import load_table, mix_weight, table_path

#: Default texture resolution, largest size, and texels per computed block of rows.
DEFAULT_SIZE = 32
MAX_SIZE = 4096
BLOCK_TEXELS = 1 << 18

_MIX_TEXT = {
    MIX_LINEAR: "0 (linear in rho; B = 0)",
    MIX_RHO2: "rho^2",
    MIX_RHO_MS: "rho_ms = rho^2 <E_F> / (1 - rho (1 - <E_F>)), <E_F>(r) = (1 + c2 r)/(1 + c1 r) (EON Eq. 15, 18)",
}


def texel_centres(size: int) -> NDArray[np.float64]:
    """(i + 0.5) / size, i = 0 .. size-1."""
    return (np.arange(size) + 0.5) / size


def _roughness_axis(name, size, index="j", where="row (0 = first scanline)"):
    """Texel-centre roughness values and their description, for an axis indexed by ``index``."""
    info = INFO[name]
    if name == "lambert":
        return np.zeros(size), "roughness ignored (Lambert): every texel along this axis is the same"
    return (
        texel_centres(size) * info.roughness_max,
        f"{info.roughness_name} = ({index} + 0.5)/{size} * {info.roughness_max!r}, {index} = {where}",
    )


def _check_size(size):
    if not (isinstance(size, (int, np.integer)) and not isinstance(size, bool) and 4 <= size <= MAX_SIZE):
        raise ValueError(f"size must be an integer in [4, {MAX_SIZE}], got {size!r}")
    return int(size)


def _rows(name, size, table, rough, start, stop):
    """Rows start..stop-1 of the directional texture, (stop - start, N, 3) float32."""
    mu = texel_centres(size)
    r = rough[start:stop, None]
    e_g, e_h = table.directional_terms(mu[None, :], r)
    E1 = e_g + mix_weight(name, 1.0, r) * e_h
    return np.stack([E1, e_g, e_h], axis=-1).astype(np.float32)


def _average_row(name, table, rough):
    a_g, a_h = table.average_terms(rough)
    A1 = a_g + mix_weight(name, 1.0, rough) * a_h
    return np.stack([A1, a_g, a_h], axis=-1)[None, :, :].astype(np.float32)


def _blocks(size):
    """Row blocks of ~BLOCK_TEXELS texels: the interpolation's float64 temporaries stay bounded."""
    step = max(1, BLOCK_TEXELS // size)
    return [(s, min(size, s + step)) for s in range(0, size, step)]


def _metadata(name, size, kind):
    info = INFO[name]
    table = load_table(name)
    meta = {
        "openpbr_diffuse:model": name,
        "openpbr_diffuse:quantity": (
            "directional albedo E(mu, roughness)"
            if kind == "directional"
            else "average albedo <E>(roughness) = 2 int E(mu) mu dmu"
        ),
        "openpbr_diffuse:channels": "R = E(rho = 1), G = e_g, B = e_h; E(rho) = rho*G + m(rho)*B",
        "openpbr_diffuse:mix": f"m(rho) = {_MIX_TEXT[info.mix]}",
        "openpbr_diffuse:rho": "R at rho = 1 (white); G, B give any rho exactly",
        "openpbr_diffuse:roughness_name": info.roughness_name,
        "openpbr_diffuse:roughness_max": 0.0 if name == "lambert" else float(info.roughness_max),
        "openpbr_diffuse:source": (
            f"reference table {table_path(name).name} ({table.meta.get('method', '')}); "
            f"interpolation error {table.interpolation_error!r}"
        ),
        "openpbr_diffuse:version": __version__,
        "openpbr_diffuse:texel_convention": "texel centres: value at (index + 0.5)/N",
    }
    if kind == "directional":
        meta["openpbr_diffuse:x_axis"] = f"mu = cos(theta_o) = (i + 0.5)/{size}, i = column"
        meta["openpbr_diffuse:y_axis"] = _roughness_axis(name, size)[1]
    else:
        meta["openpbr_diffuse:x_axis"] = _roughness_axis(name, size, "i", "column")[1]
        meta["openpbr_diffuse:y_axis"] = "single row"
    return meta


def _spec(oiio, width, height, meta):
    spec = oiio.ImageSpec(width, height, 3, oiio.FLOAT)
    spec.channelnames = ("R", "G", "B")
    spec.attribute("compression", "zip")
    for key, value in meta.items():
        spec.attribute(key, value)
    return spec


def _write_exr(path, height, width, rows, meta, shown=None):
    """Write an EXR whose scanlines come from ``rows``: an iterable of (start, stop, pixels).

    ``shown``: the name the messages give (the final file when ``path`` is its temporary)."""
    import OpenImageIO as oiio  # optional dependency (extra "exr"), imported when needed

    shown = path if shown is None else shown
    out = oiio.ImageOutput.create(path)
    if out is None:
        raise OSError(f"cannot create {shown}: {oiio.geterror()}")
    try:
        if not out.open(path, _spec(oiio, width, height, meta)):
            raise OSError(f"cannot write {shown}: {out.geterror()}")
        for start, stop, pixels in rows:
            if not out.write_scanlines(start, stop, 0, np.ascontiguousarray(pixels)):
                raise OSError(f"cannot write {shown}: {out.geterror()}")
    finally:
        out.close()


def _progress_bar(total, desc, progress):
    """A tqdm bar on stderr: ``progress`` True (always), False (never), None (when stderr is a TTY)."""
    if progress is False:
        return None
    try:
        from tqdm import tqdm  # in the "exr" extra with OpenImageIO; optional for the automatic bar
    except ImportError:
        if progress:
            raise ImportError("progress=True needs tqdm: pip install tqdm") from None
        return None

    return tqdm(
        total=total, desc=desc, unit="row", disable=None if progress is None else False, leave=False, file=sys.stderr
    )


def export_lut(
    model: str,
    directory: str | os.PathLike[str],
    size: int = DEFAULT_SIZE,
    *,
    progress: bool | None = False,
    force: bool = False,
) -> tuple[str, str]:
    """Write ``<model>_albedo.exr`` (size x size) and ``<model>_average_albedo.exr`` (size x 1).

    The directional texture is computed and written in blocks of rows (~BLOCK_TEXELS
    texels), so memory stays bounded whatever the size (4096: ~100 MB peak, measured in
    ``tests/test_broadcast_memory.py``).

    Parameters
    ----------
    model : str
        One of ``MODELS``.
    directory : path-like
        Created if missing; an existing path that is not a directory is an error.
    size : int
        Texels per axis, 4 .. 4096.
    progress : bool or None
        Progress bar (tqdm) on stderr: True, False (default), or None for "when stderr is a
        terminal".
    force : bool
        Replace the two files if they exist (regular files only).  Both are checked before
        any work and written by the rule of every output file
        (:func:`openpbr_diffuse._outfile.output_file`): never through a symbolic link, each
        through a temporary sibling that takes the file's name only once complete.

    Returns
    -------
    (str, str)
        Paths of the directional and average textures.

    Raises
    ------
    OutputFileError
        (a ``ValueError``, naming ``--export``) a file exists without ``force``, or is a
        symbolic link or not a regular file.

    Examples
    --------
    >>> import os, tempfile
    >>> d = tempfile.mkdtemp()
    >>> [os.path.basename(p) for p in export_lut("eon", d, 4)]
    ['eon_albedo.exr', 'eon_average_albedo.exr']
    >>> export_lut("eon", d, 4)
    Traceback (most recent call last):
    ...
    openpbr_diffuse._outfile.OutputExistsError: --export .../eon_albedo.exr exists: not overwritten (use --force to replace it)
    >>> len(export_lut("eon", d, 4, force=True))
    2
    """
    name = model_info(model).name
    size = _check_size(size)
    directory = os.fspath(directory)
    if os.path.exists(directory) and not os.path.isdir(directory):
        raise NotADirectoryError(errno.ENOTDIR, "export directory exists and is not a directory", directory)
    os.makedirs(directory, exist_ok=True)
    p2 = os.path.join(directory, f"{name}_albedo.exr")
    p1 = os.path.join(directory, f"{name}_average_albedo.exr")
    for p in (p2, p1):  # before any work
        check_output_file(p, option="--export", force=force)
    table = load_table(name)
    rough, _ = _roughness_axis(name, size)
    bar = _progress_bar(size, f"{name}_albedo.exr", progress)

    def rows():
        for s, e in _blocks(size):
            yield s, e, _rows(name, size, table, rough, s, e)
            if bar is not None:
                bar.update(e - s)

    with (
        output_file(p2, option="--export", force=force) as t2,
        output_file(p1, option="--export", force=force) as t1,
    ):  # both complete before either takes its name
        try:
            _write_exr(str(t2), size, size, rows(), _metadata(name, size, "directional"), p2)
        finally:
            if bar is not None:
                bar.close()
        row = [(0, 1, _average_row(name, table, rough))]
        _write_exr(str(t1), 1, size, row, _metadata(name, size, "average"), p1)
    return p2, p1


def read_exr(path: str | os.PathLike[str]) -> tuple[NDArray[np.float32], dict[str, Any]]:
    """(pixels (H, W, C) float32, metadata dict of ``openpbr_diffuse:*`` attributes)."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(os.fspath(path))
    if inp is None:
        raise OSError(f"cannot read {path}: {oiio.geterror()}")
    try:
        spec = inp.spec()
        pixels = inp.read_image(oiio.FLOAT)
        meta = {a.name: spec.getattribute(a.name) for a in spec.extra_attribs if a.name.startswith("openpbr_diffuse:")}
    finally:
        inp.close()
    return np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels), meta
