"""The conformance chart's scenes: tiles, their normals, the light and the camera.

Every scene is seen by an orthographic camera looking down -z (up +y); pixel (x, y) of the
image, origin top left, is world point ((x - W/2) s, (H/2 - y) s) with s = :data:`PIXEL`
world units per pixel.  A tile is the vertical projection of its pixel rectangle onto a
plane of normal n: a quad whose image is exactly ``rect``, whatever its tilt.  With one
distant light l and the view v = +z, the tile sees

    wo = (v.t, 0, v.n),  wi = (l.t, l.b, l.n)    in its frame (t, b, n), t along v - (v.n) n,

so a scene at one light-view angle (L.V = cos gamma) covers many (mu_i, mu_o, phi) by
tilting its tiles; the scenes together cover L.V > 0, = 0 and < 0 and grazing mu = 0.1.

Shadows and interreflection.  A grazing tile (mu_o = 0.1) reaches ~7 tile widths in z;
each tile sits on a z level of its own (a staircase: tile k at z = -sign(l_z) k dz, k
running column by column along the light's azimuth +x), so a ray from a tile towards the
light moves to columns that lie further away, below (or above) its whole z range: no
tile shadows another.  The step dz is doubled until the first-bounce bound

    sum over A of 2 mu_A area_A / (pi d_AB^2 mu_B)     (d_AB: gap between bounding spheres)

-- the irradiance tile A reflects onto B (radiance <= 2 rho mu_A E / pi over the solid
angle area_A / d^2) relative to B's own mu_B E -- is below :data:`INTERREFLECTION_MAX` for
every tile; the bound is written in chart.json.  The same sum bounds the part of a tile's
environment that the others hide in the furnace.

Example
-------
>>> scenes = build_scenes(light="distant", resolution=256)
>>> len(scenes), scenes[0].get("schema")
(5, 'openpbr-diffuse-chart/1')
>>> max(s["interreflection_bound"] for s in scenes) <= INTERREFLECTION_MAX
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

SCHEMA = "openpbr-diffuse-chart/1"
#: World units per pixel.
PIXEL = 0.01
#: Tiles per row and per column of the grid.
GRID = 16
#: The tile's side as a fraction of the grid pitch (the rest is the black gap).
TILE_FRACTION = 0.625
#: Light-view angles of the scenes, degrees (L.V = cos).
SCENE_ANGLES = (0.0, 35.0, 70.0, 110.0, 145.0)
#: Cosines of the tiles' (mu_i, mu_o) grid (0.09: grazing, below 0.1).
MU_GRID = (0.09, 0.25, 0.4, 0.55, 0.7, 0.85, 1.0)
ROUGHNESS = (0.0, 0.25, 0.5, 0.75, 1.0)
RHO = ((0.8, 0.8, 0.8), (0.9, 0.5, 0.15))
#: Albedos of the calibration ramp (roughness 0: Lambert in every model).
RAMP = tuple(float(x) for x in np.round(np.linspace(0.05, 1.0, 8), 6))
#: Irradiance of the distant light on a surface facing it (the white tile reads E / pi = 1).
IRRADIANCE = math.pi
#: Radiance of the furnace's white environment.
RADIANCE = 1.0
#: Largest first-bounce interreflection bound allowed (relative to a tile's direct light).
INTERREFLECTION_MAX = 1e-3
LIGHTS = ("distant", "point", "furnace")
#: The point light sits this many chart depths away (so mu_i E varies little over a tile).
POINT_DISTANCE = 50.0


def _unit(v):
    return v / np.linalg.norm(v)


def _frame(n):
    """(t, b, n): t along the view +z projected on the tile (any, when n = +z)."""
    v = np.array([0.0, 0.0, 1.0])
    t = v - n[2] * n
    if np.linalg.norm(t) < 1e-9:
        t = np.array([1.0, 0.0, 0.0]) - n[0] * n
    t = _unit(t)
    return t, np.cross(n, t), n


def _normals(gamma):
    """Tile normals of a scene at light-view angle gamma (radians): (n, mu_i, mu_o) list."""
    out = []
    s, c = math.sin(gamma), math.cos(gamma)
    for mo in MU_GRID:
        for mi in MU_GRID:
            if s < 1e-9:
                if mi != mo:
                    continue
                nx = math.sqrt(max(0.0, 1 - mo * mo))
            else:
                nx = (mi - mo * c) / s
            ny2 = 1.0 - nx * nx - mo * mo
            if ny2 < -1e-12:
                continue
            n = _unit(np.array([nx, math.sqrt(max(ny2, 0.0)), mo]))
            out.append((n, mi, mo))
    return out


def _calibration_normal(light_dir):
    """Facing the light when the camera sees it well (mu_o >= 0.3), else the half vector."""
    v = np.array([0.0, 0.0, 1.0])
    return light_dir.copy() if light_dir[2] >= 0.3 else _unit(light_dir + v)


def _pick(items, k):
    if len(items) <= k:
        return items
    idx = np.round(np.linspace(0, len(items) - 1, k)).astype(int)
    return [items[i] for i in idx]


def _corners(rect, n, zc, width, height):
    x0, y0, x1, y1 = rect
    xs = (np.array([x0, x1, x1, x0]) - width / 2) * PIXEL
    ys = (height / 2 - np.array([y1, y1, y0, y0])) * PIXEL
    cx, cy = xs.mean(), ys.mean()
    zs = zc - (n[0] * (xs - cx) + n[1] * (ys - cy)) / n[2]
    return np.stack([xs, ys, zs], axis=1), np.array([cx, cy, zc])


def _cone_cos(n, u, alpha):
    """Largest cos between normal n and a direction within alpha of u (0 below the horizon)."""
    ang = np.arccos(np.clip(np.einsum("...k,...k->...", n, u), -1.0, 1.0))
    return np.cos(np.clip(ang - alpha, 0.0, math.pi / 2))


def _bound(tiles, centres, radii, furnace):
    """The first-bounce interreflection bound of every tile (see the module docstring)."""
    c = np.asarray(centres)
    r = np.asarray(radii)
    n = np.array([t["normal"] for t in tiles])
    mu_i = np.array([t["mu_i"] for t in tiles])
    mu_o = np.array([t["mu_o"] for t in tiles])
    area = np.array([t["area"] for t in tiles])
    diff = c[None, :, :] - c[:, None, :]  # [b, a]: from B to A
    dist = np.linalg.norm(diff, axis=2)
    np.fill_diagonal(dist, np.inf)
    d = dist - r[:, None] - r[None, :]
    if (d <= 0).any():
        return math.inf
    u = diff / dist[..., None]
    alpha = np.arcsin(np.clip((r[:, None] + r[None, :]) / dist, 0.0, 1.0))
    cos_b = _cone_cos(n[:, None, :], u, alpha)
    if furnace:  # the share of B's environment that A hides (projected solid angle / pi)
        term = area[None, :] * cos_b / (math.pi * d**2)
        return float(term.sum(axis=1).max())
    cos_a = _cone_cos(n[None, :, :], -u, alpha)
    term = 2 * mu_i[None, :] * area[None, :] * cos_a * cos_b / (math.pi * d**2)
    return float((term.sum(axis=1) / np.maximum(np.minimum(mu_i, mu_o), 0.1)).max())


def _check_scene(gamma_deg: float, light: str, resolution: int) -> None:
    """Raise ValueError for a light, resolution or light-view angle build_scene does not take."""
    if light not in LIGHTS:
        raise ValueError(f"light: expected one of {', '.join(LIGHTS)}, got {light!r}")
    if not isinstance(resolution, int) or resolution < 256 or resolution % GRID:
        raise ValueError(f"resolution: expected a multiple of {GRID}, at least 256, got {resolution!r}")
    if not 0.0 <= gamma_deg < 180.0:
        raise ValueError(f"gamma_deg: expected an angle in [0, 180), got {gamma_deg!r}")


def _tile_specs(g: float, ldir: np.ndarray) -> list[tuple[str, np.ndarray, float, tuple[float, ...]]]:
    """(role, normal, roughness, rho) of every tile: the ramp, the white tile, then the test
    tiles (each picked normal with every roughness and rho)."""
    cal_n = _calibration_normal(ldir)
    specs: list[tuple[str, np.ndarray, float, tuple[float, ...]]] = [("ramp", cal_n, 0.0, (r, r, r)) for r in RAMP]
    specs.append(("white", cal_n, 0.0, (1.0, 1.0, 1.0)))
    geo = _pick(_normals(g), (GRID * GRID - len(specs)) // (len(ROUGHNESS) * len(RHO)))
    for n, _, _ in geo:
        for rough in ROUGHNESS:
            for rho in RHO:
                specs.append(("test", n, rough, rho))
    return specs


def _tiles(specs: list, ldir: np.ndarray, pitch: int, size: int) -> list[dict[str, Any]]:
    """The tiles' documents in grid order (a snake, column by column), with the working
    entries ``_wi``, ``_wo``, ``_colrow``, ``_k`` and ``area`` that :func:`_finish_tile` drops."""
    off = (pitch - size) // 2
    v = np.array([0.0, 0.0, 1.0])
    tiles: list[dict[str, Any]] = []
    for k, (role, n, rough, rho) in enumerate(specs):
        col, row = k // GRID, k % GRID
        if col % 2:  # a snake: consecutive tiles are neighbours
            row = GRID - 1 - row
        rect = [col * pitch + off, row * pitch + off, col * pitch + off + size, row * pitch + off + size]
        t, b, nn = _frame(n)
        wo = np.array([v @ t, v @ b, v @ nn])
        wi = np.array([ldir @ t, ldir @ b, ldir @ nn])
        tiles.append(
            {
                "id": f"t{k:03d}",
                "rect": rect,
                "role": role,
                "roughness": float(rough),
                "rho": [float(x) for x in rho],
                "normal": [float(x) for x in n],
                "mu_i": float(wi[2]),
                "mu_o": float(wo[2]),
                "area": float((size * PIXEL) ** 2 / n[2]),
                "_wi": wi,
                "_wo": wo,
                "_colrow": (col, row),
                "_k": k,
            }
        )
    return tiles


def _staircase(
    tiles: list[dict[str, Any]], normals: list[np.ndarray], ldir: np.ndarray, size: int, resolution: int, furnace: bool
) -> tuple[list[np.ndarray], list[np.ndarray], float]:
    """The tiles' corners and centres on the staircase (ordered along the light's azimuth +x,
    column by column) whose step is grown until the interreflection bound is small enough,
    and that bound."""
    sign = -1.0 if ldir[2] < 0 else 1.0
    half = size * PIXEL / 2
    reach = max(half * (abs(n[0]) + abs(n[1])) / n[2] for n in normals)
    dz = 2.0 * reach + size * PIXEL
    while True:
        centres, radii, corners = [], [], []
        for tile in tiles:
            zc = -sign * dz * tile["_k"]
            cs, c = _corners(tile["rect"], np.array(tile["normal"]), zc, resolution, resolution)
            corners.append(cs)
            centres.append(c)
            radii.append(float(np.linalg.norm(cs - c, axis=1).max()))
        bound = _bound(tiles, centres, radii, furnace)
        if bound <= INTERREFLECTION_MAX:
            return corners, centres, bound
        dz *= 1.25


def _light(light: str, ldir: np.ndarray, zs: np.ndarray, depth: float, width: int) -> dict[str, Any]:
    """The scene's light document: a distant light along ``ldir``, a point light far along it
    from the chart's centre, or the furnace."""
    if light == "distant":
        return {"kind": "distant", "direction": [float(x) for x in ldir], "irradiance": IRRADIANCE}
    if light == "point":
        dist = POINT_DISTANCE * max(depth, width * PIXEL)
        centre = np.array([0.0, 0.0, 0.5 * (zs.max() + zs.min())])
        pos = centre + dist * ldir
        return {
            "kind": "point",
            "position": [float(x) for x in pos],
            "intensity": IRRADIANCE * dist * dist,
            "irradiance": IRRADIANCE,
            "irradiance_note": "irradiance = intensity / d^2 on a surface facing the light at distance d",
        }
    return {"kind": "furnace", "radiance": RADIANCE, "irradiance": math.pi * RADIANCE}


def _finish_tile(tile: dict[str, Any], cs: np.ndarray, c: np.ndarray, light: dict[str, Any]) -> None:
    """Turn a working tile into its chart.json entry: corners, centre, wo and the light it
    receives (wi; for a point light also mu_i, the irradiance at its centre and its variation)."""
    wi, wo = tile.pop("_wi"), tile.pop("_wo")
    tile.pop("_colrow")
    tile.pop("_k")
    tile.pop("area")
    tile["corners"] = [[float(x) for x in p] for p in cs]
    tile["centre"] = [float(x) for x in c]
    tile["wo"] = [float(x) for x in wo]
    if light["kind"] == "distant":
        tile["wi"] = [float(x) for x in wi]
    elif light["kind"] == "point":
        pos = np.array(light["position"])
        n = np.array(tile["normal"])
        vals = []
        for p in list(cs) + [c]:
            d = pos - p
            vals.append(max(float(n @ d), 0.0) / float(np.linalg.norm(d)) ** 3)
        tile["wi"] = [float(x) for x in _local(_unit(pos - c), n)]
        tile["mu_i"] = tile["wi"][2]
        tile["irradiance"] = float(light["intensity"] * vals[-1] / max(tile["wi"][2], 1e-12))
        tile["variation"] = float(max(abs(x / vals[-1] - 1.0) for x in vals[:-1]))
    else:
        tile.pop("mu_i")
    tile["expected_rel"] = _calibration_value(tile, light)


def build_scene(gamma_deg: float, light: str = "distant", resolution: int = 1024, index: int = 0) -> dict[str, Any]:
    """One scene of the chart as its chart.json document (a dict; see docs/reference/chart-schema.md).

    Parameters
    ----------
    gamma_deg : float
        Angle between the light and the view, degrees in [0, 180).
    light : {"distant", "point", "furnace"}
    resolution : int
        Image width = height in pixels, a multiple of 16, at least 256.
    index : int
        The scene's number (its id ``scene_NN``).

    Example
    -------
    >>> s = build_scene(35.0, resolution=256)
    >>> roles = [t["role"] for t in s["tiles"]]
    >>> roles.count("ramp"), roles.index("white")
    (8, 8)
    """
    _check_scene(gamma_deg, light, resolution)
    g = math.radians(gamma_deg)
    ldir = np.array([math.sin(g), 0.0, math.cos(g)])
    width = height = resolution
    pitch = resolution // GRID
    size = int(round(pitch * TILE_FRACTION))
    specs = _tile_specs(g, ldir)
    tiles = _tiles(specs, ldir, pitch, size)
    corners, centres, bound = _staircase(tiles, [n for _, n, _, _ in specs], ldir, size, resolution, light == "furnace")
    zs = np.concatenate([c[:, 2] for c in corners])
    depth = float(zs.max() - zs.min())
    scene: dict[str, Any] = {
        "schema": SCHEMA,
        "id": f"scene_{index:02d}",
        "width": width,
        "height": height,
        "units": "world units (metres in USD, glTF and Blender); one pixel is 0.01",
        "light_view_angle_deg": float(gamma_deg),
        "interreflection_bound": bound,
        "camera": {
            "kind": "orthographic",
            "position": [0.0, 0.0, float(zs.max() + 1.0)],
            "direction": [0.0, 0.0, -1.0],
            "up": [0.0, 1.0, 0.0],
            "extent": [width * PIXEL, height * PIXEL],
            "near": 0.5,
            "far": depth + 2.0,
        },
        "light": _light(light, ldir, zs, depth, width),
    }
    for tile, cs, c in zip(tiles, corners, centres, strict=True):
        _finish_tile(tile, cs, c, scene["light"])
    scene["tiles"] = tiles
    return scene


def _local(d, n):
    t, b, nn = _frame(n)
    return np.array([d @ t, d @ b, d @ nn])


def _calibration_value(tile, light):
    """A ramp / white tile's expected value divided by the white tile facing the light's
    E / pi (distant, point) or by L (furnace): rho mu_i (Lambert).  None for a test tile."""
    if tile["role"] == "test":
        return None
    rho = tile["rho"][0]
    if light["kind"] == "furnace":
        return rho
    return rho * tile["mu_i"]


def build_scenes(light: str = "distant", resolution: int = 1024) -> list[dict[str, Any]]:
    """Every scene of the chart (one per angle of :data:`SCENE_ANGLES`; the furnace has one).

    Example
    -------
    >>> len(build_scenes("furnace", 256))
    1
    """
    angles = SCENE_ANGLES if light != "furnace" else (0.0,)
    return [build_scene(a, light, resolution, i) for i, a in enumerate(angles)]


__all__ = ["SCHEMA", "build_scene", "build_scenes", "LIGHTS", "RAMP", "IRRADIANCE", "RADIANCE", "PIXEL"]
