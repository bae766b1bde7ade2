"""``load_materials`` and ``BUNDLED_MATERIALS``: the readers' public entry points."""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from pathlib import Path

USD_SUFFIXES = (".usda", ".usdc", ".usd", ".usdz")
MTLX_SUFFIXES = (".mtlx",)
MATERIAL_SUFFIXES = USD_SUFFIXES + MTLX_SUFFIXES


def _bundled():
    """The bundled material library: ``openpbr_diffuse/materials`` in an installed wheel,
    the repository's top-level ``materials/`` in a checkout."""
    here = Path(__file__).resolve().parent.parent
    installed = here / "materials"
    if installed.is_dir():
        return installed
    return here.parent / "materials"


#: Folder of the bundled material library (works after a non-editable install).
BUNDLED_MATERIALS = _bundled()


def find_material_files(paths: Iterable[str | os.PathLike[str]]) -> list[Path]:
    """Material files (USD / MaterialX) among ``paths``, folders searched recursively, sorted."""
    out = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            out += sorted(f for f in p.rglob("*") if f.suffix.lower() in MATERIAL_SUFFIXES and f.is_file())
        else:
            out.append(p)
    return out


def _check_uv(uv):
    try:
        u, v = (float(x) for x in uv)
    except (TypeError, ValueError):
        raise TypeError(f"uv must be two numbers (u, v), got {uv!r}") from None
    if not (abs(u) < 1e30 and abs(v) < 1e30):
        raise ValueError(f"uv must be finite, got {uv!r}")
    return (u, v)


def _check_variants(variants: dict | list | None) -> dict[str, str]:
    if variants is None:
        return {}
    if isinstance(variants, dict):
        items = list(variants.items())
    else:
        items = []
        for s in variants:
            if not isinstance(s, str) or "=" not in s:
                raise ValueError(f"variants: expected SET=VALUE, got {s!r}")
            k, v = s.split("=", 1)
            items.append((k.strip(), v.strip()))
    for k, v in items:
        if not isinstance(k, str) or not isinstance(v, str) or not k:
            raise ValueError(f"variants: expected set name and value strings, got {k!r}={v!r}")
    return dict(items)


def load_materials(
    path: str | os.PathLike,
    *,
    time: float | None = None,
    variants: dict | list | None = None,
    uv: tuple = (0.5, 0.5),
    material: str | None = None,
    purpose: str = "full",
) -> list:
    """Read the materials of a USD stage or MaterialX document.

    Parameters
    ----------
    path : str or Path
        ``.usda`` / ``.usdc`` / ``.usd`` / ``.usdz`` or ``.mtlx``.  The file is never modified.
    time : float, optional
        USD time code for time-sampled inputs (default: the default time; an input with only
        time samples then takes its earliest sample, said in its provenance).
    variants : dict or list of "SET=VALUE", optional
        Variant selections (USD), applied in the session layer.
    uv : (u, v)
        Where textures are sampled (v up).
    material : str, optional
        A material's prim path or name (MaterialX: node name), or the path of a geometry prim
        whose bound material (``ComputeBoundMaterial``, ``purpose``) is wanted.
    purpose : str
        Material purpose for bindings: "full" (default, falling back to all-purpose),
        "preview" or "" (all-purpose).

    Returns
    -------
    list of Material

    Raises
    ------
    FileNotFoundError, ValueError, TypeError
        Missing / unreadable / malformed file, unknown prim, unknown variant, connection
        cycle, wrong value type: one-line messages naming the file.

    Examples
    --------
    >>> mats = load_materials(BUNDLED_MATERIALS / "clay_rough.mtlx")
    >>> mats[0].parameters["base_diffuse_roughness"].value
    1.0
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike (a .usd* or .mtlx file), got {type(path).__name__}")
    path = os.fspath(path)
    if not isinstance(path, str):
        raise TypeError(f"path must name the file as text, got {type(path).__name__}")
    uv = _check_uv(uv)
    variants = _check_variants(variants)
    if time is not None:
        try:
            time = float(time)
        except (TypeError, ValueError):
            raise TypeError(f"time must be a number, got {time!r}") from None
    if material is not None and not isinstance(material, str):
        raise TypeError(f"material must be a string (prim path or name), got {type(material).__name__}")
    if purpose not in ("full", "preview", ""):
        raise ValueError(f"purpose must be 'full', 'preview' or '' (all-purpose), got {purpose!r}")
    suffix = Path(path).suffix.lower()
    if not os.path.exists(path):
        raise FileNotFoundError(f"{path}: no such file")
    if os.path.isdir(path):
        raise IsADirectoryError(f"{path}: is a directory, expected a .usd* or .mtlx file")
    mode = os.stat(path).st_mode
    if not stat.S_ISREG(mode):
        # a FIFO or device would block or never end: refused by its type, before any open
        kind = (
            "a FIFO"
            if stat.S_ISFIFO(mode)
            else (
                "a device"
                if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
                else "a socket"
                if stat.S_ISSOCK(mode)
                else "not a regular file"
            )
        )
        raise ValueError(f"{path}: is {kind}, expected a regular .usd* or .mtlx file")
    if suffix in MTLX_SUFFIXES:
        if variants:
            raise ValueError(f"{path}: variants apply to USD stages, not MaterialX documents")
        from . import materialx

        mats = materialx.load(path, uv=uv, material=material)
    elif suffix in USD_SUFFIXES:
        from . import usd

        mats = usd.load(path, time=time, variants=variants, uv=uv, material=material, purpose=purpose)
    else:
        raise ValueError(
            f"{path}: unknown file type {suffix or '(none)'}; expected one of {', '.join(MATERIAL_SUFFIXES)}"
        )
    if material is not None and not mats:
        raise ValueError(f"{path}: no material or prim {material!r}")
    return mats


__all__ = ["load_materials", "BUNDLED_MATERIALS", "find_material_files", "MATERIAL_SUFFIXES"]
