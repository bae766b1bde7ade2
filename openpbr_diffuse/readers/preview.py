"""Preview renders of a material: a sphere under a directional light and under a uniform
white environment (the furnace), side by side, written with OpenImageIO.

Left: the sphere under a directional light (from the upper left, irradiance pi at normal
incidence, so a white Lambertian surface facing the light is 1); right: under a uniform white
environment (each pixel shows the directional albedo at its view angle). Orthographic camera
along -z, 2x2 supersampling, black background, alpha = coverage. EXR: linear ACEScg (the
readers' working space), float. PNG: converted to sRGB with OpenImageIO's colorconvert
(ACEScg -> srgb_rec709_scene), 8 bit. Vectorised: the whole image is one call of the node.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._outfile import output_file
from .evaluate import brdf_and_lobes

if TYPE_CHECKING:
    from .material import Material

LIGHT = np.array([-1.0, 1.0, 1.0]) / np.sqrt(3.0)
VIEW = np.array([0.0, 0.0, 1.0])


def local_directions(
    normals: NDArray[np.float64], view: NDArray[np.float64] = VIEW, light: NDArray[np.float64] = LIGHT
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(wi, wo) in each point's local frame (normal +z, wo in the xz-plane), from world normals (P, 3)."""
    n = normals
    mu_o = n @ view
    mu_i = n @ light
    vt = view[None, :] - mu_o[:, None] * n
    lt = light[None, :] - mu_i[:, None] * n
    sv = np.linalg.norm(vt, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ex = np.where(sv[:, None] > 1e-12, vt / np.where(sv > 1e-12, sv, 1.0)[:, None], 0.0)
    # a tangent frame where the view has no y component; when the view is along n, any frame
    ex = np.where(sv[:, None] > 1e-12, ex, _any_tangent(n))
    ey = np.cross(n, ex)
    wo = np.stack([sv, np.zeros_like(sv), mu_o], axis=1)
    wi = np.stack([np.einsum("ij,ij->i", lt, ex), np.einsum("ij,ij->i", lt, ey), mu_i], axis=1)
    return _unit(wi), _unit(wo)


def _any_tangent(n):
    a = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    t = np.cross(a, n)
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def _unit(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def render_image(material: Material, size: int = 256, supersample: int = 2) -> NDArray[np.float32]:
    """(H, 2H, 4) float32 image: directional light | furnace, ACEScg, alpha = coverage."""
    node = material.node()
    if node is None:
        raise ValueError(f"render: material {material.path} is not supported ({'; '.join(material.unsupported)})")
    if not isinstance(size, (int, np.integer)) or not 8 <= size <= 4096:
        raise ValueError(f"size must be an integer in [8, 4096], got {size!r}")
    S = size * supersample
    c = (np.arange(S) + 0.5) / S * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    inside = r2 < 1.0
    n = np.stack([x[inside], y[inside], np.sqrt(1.0 - r2[inside])], axis=1)
    wi, wo = local_directions(n)
    f, furnace, _, _ = brdf_and_lobes(node, wi, wo)  # one compiled pass for both halves
    lit = np.where(wi[:, 2:3] > 0.0, f * np.pi * wi[:, 2:3], 0.0)
    out = np.zeros((S, 2 * S, 4))
    left = np.zeros((S, S, 3))
    right = np.zeros((S, S, 3))
    left[inside] = lit
    right[inside] = furnace
    out[:, :S, :3], out[:, S:, :3] = left, right
    out[:, :S, 3] = out[:, S:, 3] = inside
    img = out.reshape(size, supersample, 2 * size, supersample, 4).mean(axis=(1, 3))
    return img.astype(np.float32)


def write_image(
    img: ArrayLike,
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
    option: str = "--out",
) -> Path:
    """Write ``img`` to ``path``: EXR linear ACEScg float; PNG/other sRGB-encoded 8 bit
    (OpenImageIO colorconvert).

    By the rule of every output file (:func:`openpbr_diffuse._outfile.output_file`): an
    existing file is replaced only with ``force`` (a regular file, never a symbolic link or
    one of ``inputs``), through a temporary sibling that keeps the suffix.  Returns the
    absolute path written.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> write_image(np.ones((8, 16, 4), np.float32), d / "x.exr").name
    'x.exr'
    >>> [p.name for p in d.iterdir()]
    ['x.exr']
    """
    import OpenImageIO as oiio

    text = os.fspath(path)
    ext = os.path.splitext(text)[1].lower()
    if ext not in (".exr", ".png", ".jpg", ".jpeg", ".tif", ".tiff"):
        raise ValueError(f"--out must end in .exr or .png (also .jpg, .tif), got {text!r}")
    buf = oiio.ImageBuf(np.ascontiguousarray(img))
    with output_file(path, option=option, force=force, inputs=inputs) as tmp:
        if ext == ".exr":
            buf.specmod().attribute("oiio:ColorSpace", "ACEScg")
            ok = buf.write(str(tmp), "float")
        else:
            conv = oiio.ImageBufAlgo.colorconvert(buf, "ACEScg", "srgb_rec709_scene")
            if conv.has_error:
                raise OSError(f"render: colour conversion failed: {conv.geterror()}")
            ok = conv.write(str(tmp), "uint8")
            buf = conv
        if not ok:
            why = (buf.geterror() or oiio.geterror()).replace(str(tmp), text)  # name the file asked for
            raise OSError(f"render: cannot write {text}: {' '.join(why.split())}")
    return Path(os.path.abspath(text))


__all__ = ["render_image", "write_image", "local_directions", "LIGHT", "VIEW"]
