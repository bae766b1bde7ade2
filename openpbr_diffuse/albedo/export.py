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
import os

import numpy as np

from .._version import __version__
from ..models.registry import INFO, MIX_LINEAR, MIX_RHO2, MIX_RHO_MS, model_info
from ..models.tables import load_table, mix_weight

#: Default texture resolution.
DEFAULT_SIZE = 32

_MIX_TEXT = {MIX_LINEAR: "0 (linear in rho; B = 0)", MIX_RHO2: "rho^2",
             MIX_RHO_MS: "rho_ms = rho^2 <E_F> / (1 - rho (1 - <E_F>)), <E_F>(r) = (1 + c2 r)/(1 + c1 r) (EON Eq. 15, 18)"}


def texel_centres(size):
    """(i + 0.5) / size, i = 0 .. size-1."""
    return (np.arange(size) + 0.5) / size


def _roughness_axis(name, size):
    info = INFO[name]
    if name == "lambert":
        return np.zeros(size), "roughness ignored (Lambert): every row is the same"
    return (texel_centres(size) * info.roughness_max,
            f"{info.roughness_name} = (j + 0.5)/{size} * {info.roughness_max:.10g}, j = row (0 = first scanline)")


def lut_values(model, size=DEFAULT_SIZE):
    """The two textures as arrays: (N, N, 3) directional and (1, N, 3) average, float32."""
    name = model_info(model).name
    if not (isinstance(size, (int, np.integer)) and 4 <= size <= 4096):
        raise ValueError(f"size must be an integer in [4, 4096], got {size!r}")
    table = load_table(name)
    mu = texel_centres(size)
    rough, _ = _roughness_axis(name, size)
    e_g, e_h = table.directional_terms(mu[None, :], rough[:, None])
    E1 = e_g + mix_weight(name, 1.0, rough[:, None]) * e_h
    a_g, a_h = table.average_terms(rough)
    A1 = a_g + mix_weight(name, 1.0, rough) * a_h
    img2d = np.stack([E1, e_g, e_h], axis=-1).astype(np.float32)
    img1d = np.stack([A1, a_g, a_h], axis=-1)[None, :, :].astype(np.float32)
    return img2d, img1d


def _metadata(name, size, kind):
    info = INFO[name]
    table = load_table(name)
    _, y_axis = _roughness_axis(name, size)
    meta = {
        "openpbr_diffuse:model": name,
        "openpbr_diffuse:quantity": ("directional albedo E(mu, roughness)" if kind == "directional"
                                     else "average albedo <E>(roughness) = 2 int E(mu) mu dmu"),
        "openpbr_diffuse:channels": "R = E(rho = 1), G = e_g, B = e_h; E(rho) = rho*G + m(rho)*B",
        "openpbr_diffuse:mix": f"m(rho) = {_MIX_TEXT[info.mix]}",
        "openpbr_diffuse:rho": "R at rho = 1 (white); G, B give any rho exactly",
        "openpbr_diffuse:roughness_name": info.roughness_name,
        "openpbr_diffuse:roughness_max": 0.0 if name == "lambert" else float(info.roughness_max),
        "openpbr_diffuse:source": (f"reference tables ({table.meta.get('method', '')[:80]}...), "
                                   f"interpolation error {table.interpolation_error:.1e}"),
        "openpbr_diffuse:version": __version__,
        "openpbr_diffuse:texel_convention": "texel centres: value at (index + 0.5)/N",
    }
    if kind == "directional":
        meta["openpbr_diffuse:x_axis"] = f"mu = cos(theta_o) = (i + 0.5)/{size}, i = column"
        meta["openpbr_diffuse:y_axis"] = y_axis
    else:
        meta["openpbr_diffuse:x_axis"] = y_axis.replace("j = row (0 = first scanline)", "i = column")
        meta["openpbr_diffuse:y_axis"] = "single row"
    return meta


def _write_exr(path, pixels, meta):
    import OpenImageIO as oiio  # optional dependency (extra "exr"), imported when needed

    height, width, channels = pixels.shape
    spec = oiio.ImageSpec(width, height, channels, oiio.FLOAT)
    spec.channelnames = ("R", "G", "B")
    spec.attribute("compression", "zip")
    for key, value in meta.items():
        spec.attribute(key, value)
    out = oiio.ImageOutput.create(path)
    if out is None:
        raise OSError(f"cannot create {path}: {oiio.geterror()}")
    try:
        if not out.open(path, spec) or not out.write_image(np.ascontiguousarray(pixels)):
            raise OSError(f"cannot write {path}: {out.geterror()}")
    finally:
        out.close()


def export_lut(model, directory, size=DEFAULT_SIZE):
    """Write ``<model>_albedo.exr`` (size x size) and ``<model>_average_albedo.exr`` (size x 1).

    Parameters
    ----------
    model : str
        One of ``MODELS``.
    directory : path-like
        Created if missing.
    size : int
        Texels per axis, 4 .. 4096.

    Returns
    -------
    (str, str)
        Paths of the directional and average textures.
    """
    name = model_info(model).name
    img2d, img1d = lut_values(name, size)
    directory = os.fspath(directory)
    os.makedirs(directory, exist_ok=True)
    p2 = os.path.join(directory, f"{name}_albedo.exr")
    p1 = os.path.join(directory, f"{name}_average_albedo.exr")
    _write_exr(p2, img2d, _metadata(name, size, "directional"))
    _write_exr(p1, img1d, _metadata(name, size, "average"))
    return p2, p1


def read_exr(path):
    """(pixels (H, W, C) float32, metadata dict of ``openpbr_diffuse:*`` attributes)."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(os.fspath(path))
    if inp is None:
        raise OSError(f"cannot read {path}: {oiio.geterror()}")
    try:
        spec = inp.spec()
        pixels = inp.read_image(oiio.FLOAT)
        meta = {a.name: spec.getattribute(a.name) for a in spec.extra_attribs
                if a.name.startswith("openpbr_diffuse:")}
    finally:
        inp.close()
    return np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels), meta
