"""The image a conforming renderer makes of a chart scene, computed from chart.json alone.

Every tile's pixels get its expected linear value (edges sharp, no anti-aliasing; the
gaps are black):

- distant light: f(wi, wo) mu_i E, with the tile's ``wi``, ``wo`` and the light's
  ``irradiance`` E;
- point light: per pixel, the point of the tile's quad under the pixel centre, its own
  wi towards the light and irradiance I cos / d^2;
- furnace: E(mu_o) L, the directional albedo at the tile's mu_o times the environment's
  radiance.

Example
-------
>>> from openpbr_diffuse.chart.layout import build_scene
>>> s = build_scene(35.0, resolution=256)
>>> img = expected_image(s)
>>> white = next(t for t in s["tiles"] if t["role"] == "white")
>>> x0, y0, _, _ = white.get("rect")
>>> img.shape, round(float(img[y0, x0, 0]), 6)   # the white tile: E/pi
((256, 256, 3), 1.0)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..models import directional_albedo, evaluate


def _frame(n):
    v = np.array([0.0, 0.0, 1.0])
    t = v - n[2] * n
    if np.linalg.norm(t) < 1e-9:
        t = np.array([1.0, 0.0, 0.0]) - n[0] * n
    t = t / np.linalg.norm(t)
    return t, np.cross(n, t), n


def _point_tile(tile, light, width, height, pixel, model):
    """(h, w, 3) expected values of a tile under a point light, per pixel centre."""
    x0, y0, x1, y1 = tile["rect"]
    n = np.asarray(tile["normal"], float)
    c = np.asarray(tile["centre"], float)
    xs = (np.arange(x0, x1) + 0.5 - width / 2) * pixel
    ys = (height / 2 - (np.arange(y0, y1) + 0.5)) * pixel
    X, Y = np.meshgrid(xs, ys)
    Z = c[2] - (n[0] * (X - c[0]) + n[1] * (Y - c[1])) / n[2]
    d = np.asarray(light["position"], float) - np.stack([X, Y, Z], axis=-1)
    dist = np.linalg.norm(d, axis=-1)
    u = d / dist[..., None]
    t, b, nn = _frame(n)
    wi = np.stack([u @ t, u @ b, u @ nn], axis=-1)
    wo = np.broadcast_to(np.asarray(tile["wo"], float), wi.shape)
    f = evaluate(model, wi, wo, np.full(wi.shape[:-1], tile["roughness"]), np.asarray(tile["rho"], float))
    irr = light["intensity"] * np.maximum(wi[..., 2], 0.0) / dist**2
    return f * irr[..., None]


def tile_values(scene: dict[str, Any], model: str = "eon") -> np.ndarray:
    """(n_tiles, 3) expected linear value of every tile (at its centre for a point light).

    Example
    -------
    >>> from openpbr_diffuse.chart.layout import build_scene
    >>> v = tile_values(build_scene(0.0, "furnace", 256))
    >>> round(float(v[8, 0]), 6)                     # the white tile in the furnace: L
    1.0
    """
    tiles = scene["tiles"]
    light = scene["light"]
    rough = np.array([t["roughness"] for t in tiles], float)
    rho = np.array([t["rho"] for t in tiles], float)
    wo = np.array([t["wo"] for t in tiles], float)
    if light["kind"] == "furnace":
        return directional_albedo(model, wo[:, 2], rough, rho) * float(light["radiance"])
    wi = np.array([t["wi"] for t in tiles], float)
    if light["kind"] == "point":
        irr = np.array([t["irradiance"] for t in tiles], float)
    else:
        irr = np.full(len(tiles), float(light["irradiance"]))
    return evaluate(model, wi, wo, rough, rho) * (np.maximum(wi[:, 2], 0.0) * irr)[:, None]


def expected_image(scene: dict[str, Any], model: str = "eon") -> np.ndarray:
    """(height, width, 3) float32 linear image of the scene as a conforming renderer makes it.

    Parameters
    ----------
    scene : dict
        A chart.json document (:func:`.layout.build_scene`, or read by :func:`.schema.read_chart`).
    model : str
        The model of the test tiles (a name of ``openpbr_diffuse.MODELS``; default EON).

    Example
    -------
    >>> from openpbr_diffuse.chart.layout import build_scene
    >>> expected_image(build_scene(70.0, "point", 256)).dtype
    dtype('float32')
    """
    from .layout import PIXEL

    w, h = int(scene["width"]), int(scene["height"])
    img = np.zeros((h, w, 3), np.float32)
    light = scene["light"]
    values = None if light["kind"] == "point" else tile_values(scene, model)
    for k, tile in enumerate(scene["tiles"]):
        x0, y0, x1, y1 = tile["rect"]
        if values is None:
            img[y0:y1, x0:x1] = _point_tile(tile, light, w, h, PIXEL, model)
        else:
            img[y0:y1, x0:x1] = values[k]
    return img


__all__ = ["expected_image", "tile_values"]
