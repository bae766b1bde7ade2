"""Reading and checking a chart.json document (schema ``openpbr-diffuse-chart/1``).

The schema is documented in docs/reference/chart-schema.md; this module checks what the
grader relies on and raises ``ValueError`` naming the file and the field otherwise.

Example
-------
>>> import json, pathlib, tempfile
>>> from openpbr_diffuse.chart.layout import build_scene
>>> p = pathlib.Path(tempfile.mkdtemp()) / "chart.json"
>>> _ = p.write_text(json.dumps(build_scene(35.0, resolution=256)))
>>> read_chart(p).get("light").get("kind")
'distant'
>>> _ = p.write_text('{"schema": "other/1"}')
>>> read_chart(p)
Traceback (most recent call last):
...
ValueError: --chart ...chart.json: schema 'other/1' is not openpbr-diffuse-chart/1
"""

from __future__ import annotations

import json
import math
import os
from typing import Any

from .layout import LIGHTS, SCHEMA

#: chart.json files larger than this are refused (a chart of 256 tiles is ~150 kB).
MAX_BYTES = 16 * 1024 * 1024
ROLES = ("test", "ramp", "white")


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _vec(tile, key, n, where):
    v = tile.get(key)
    if not (isinstance(v, list) and len(v) == n and all(_finite(x) for x in v)):
        raise ValueError(f"{where}: {key} must be a list of {n} finite numbers")


def validate(doc: Any, where: str = "chart") -> dict[str, Any]:
    """``doc`` when it is a usable chart document, else ``ValueError`` naming the field.

    >>> validate({"schema": "openpbr-diffuse-chart/1", "width": 0})
    Traceback (most recent call last):
    ...
    ValueError: chart: width must be an integer in [1, 65536]
    """
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: expected a JSON object")
    if doc.get("schema") != SCHEMA:
        raise ValueError(f"{where}: schema {doc.get('schema')!r} is not {SCHEMA}")
    for key in ("width", "height"):
        v = doc.get(key)
        if not (isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= 65536):
            raise ValueError(f"{where}: {key} must be an integer in [1, 65536]")
    light = doc.get("light")
    if not isinstance(light, dict) or light.get("kind") not in LIGHTS:
        raise ValueError(f"{where}: light.kind must be one of {', '.join(LIGHTS)}")
    need = {"distant": ("irradiance",), "point": ("intensity", "irradiance"), "furnace": ("radiance",)}[light["kind"]]
    for key in need:
        if not (_finite(light.get(key)) and light[key] > 0):
            raise ValueError(f"{where}: light.{key} must be a positive number")
    if light["kind"] == "point":
        _vec(light, "position", 3, f"{where}: light")
    tiles = doc.get("tiles")
    if not isinstance(tiles, list) or not tiles:
        raise ValueError(f"{where}: tiles must be a non-empty list")
    for i, t in enumerate(tiles):
        at = f"{where}: tiles[{i}]"
        if not isinstance(t, dict):
            raise ValueError(f"{at}: expected an object")
        if t.get("role") not in ROLES:
            raise ValueError(f"{at}: role must be one of {', '.join(ROLES)}")
        r = t.get("rect")
        if not (isinstance(r, list) and len(r) == 4 and all(isinstance(x, int) and not isinstance(x, bool) for x in r)):
            raise ValueError(f"{at}: rect must be 4 integers [x0, y0, x1, y1]")
        if not (0 <= r[0] < r[2] <= doc["width"] and 0 <= r[1] < r[3] <= doc["height"]):
            raise ValueError(f"{at}: rect {r} is not inside the {doc['width']}x{doc['height']} image")
        if not (_finite(t.get("roughness")) and t["roughness"] >= 0):
            raise ValueError(f"{at}: roughness must be a number >= 0")
        _vec(t, "rho", 3, at)
        _vec(t, "wo", 3, at)
        if light["kind"] != "furnace":
            _vec(t, "wi", 3, at)
        if light["kind"] == "point":
            _vec(t, "normal", 3, at)
            _vec(t, "centre", 3, at)
            if not (_finite(t.get("irradiance")) and t["irradiance"] > 0):
                raise ValueError(f"{at}: irradiance must be a positive number (point light)")
        t.setdefault("id", f"tile{i}")
    if not any(t["role"] in ("ramp", "white") for t in tiles):
        raise ValueError(f"{where}: no ramp or white tile to calibrate the exposure on")
    if not any(t["role"] == "test" for t in tiles):
        raise ValueError(f"{where}: no test tile")
    return doc


def read_chart(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read and check a chart.json file (never modified); ``ValueError`` names what is wrong.

    >>> read_chart("/nonexistent/chart.json")
    Traceback (most recent call last):
    ...
    FileNotFoundError: [Errno 2] No such file or directory: '/nonexistent/chart.json'
    """
    where = f"--chart {os.fspath(path)}"
    with open(path, "rb") as fh:
        raw = fh.read(MAX_BYTES + 1)
    if len(raw) > MAX_BYTES:
        raise ValueError(f"{where}: larger than {MAX_BYTES // (1024 * 1024)} MB: not a chart")
    try:
        doc = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{where}: not JSON ({exc})") from None
    return validate(doc, where)


__all__ = ["read_chart", "validate", "MAX_BYTES", "ROLES"]
