"""Shipped reference tables of the ColorChecker colour shift (``data/colorshift_checker_*.csv``).

One file per working space (D65, CIE 1931 2 degree observer, 380-780 nm / 5 nm): the 24
measured 'BabelColor Average' spectra x ``TABLE_ROUGHNESS`` x ``TABLE_MU``, every field of
``validation.ColourShift.rows`` (RGB fields as three columns ``_r _g _b``).  The ``#`` header
states method, grid, rounding, the check against the quadrature albedo tables, the library and
colour-science versions and the regeneration command ``python tools/make_colorshift_table.py``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._csv import read_headed_csv
from .validation import RGB_FIELDS, SCALAR_FIELDS

if TYPE_CHECKING:
    from .validation import ColourShift

DATA = Path(__file__).resolve().parents[1] / "data"
TABLE_WORKING_SPACES = ("lin_rec709", "acescg")
TABLE_ILLUMINANT = "D65"
TABLE_ROUGHNESS = tuple(k / 8 for k in range(9))
TABLE_THETA_DEG = (0.0, 30.0, 60.0, 75.0, 84.0)
TABLE_MU = tuple(float(np.round(np.cos(np.radians(t)), 12)) for t in TABLE_THETA_DEG)
DECIMALS = 10
COLUMNS = (
    ["patch", "roughness", "theta_deg", "mu", "rho_rgb_clipped"]
    + [f"{f}_{c}" for f in RGB_FIELDS for c in "rgb"]
    + list(SCALAR_FIELDS)
)


def table_path(working_space: str) -> Path:
    """Path of the shipped table for ``working_space`` (one of ``TABLE_WORKING_SPACES``)."""
    if working_space not in TABLE_WORKING_SPACES:
        raise ValueError(f"working_space must be one of {', '.join(TABLE_WORKING_SPACES)}; got {working_space!r}")
    return DATA / f"colorshift_checker_{working_space}.csv"


def table_lines(result: ColourShift) -> list[str]:
    """CSV data lines (header row first) of a ColourShift on the table grid."""
    theta = dict(zip(TABLE_MU, TABLE_THETA_DEG))
    out = [",".join(COLUMNS)]
    for row in result.rows():
        vals = [
            row["patch"],
            f"{row['roughness']:.6f}",
            f"{theta.get(row['mu'], float('nan')):g}",
            f"{row['mu']:.12f}",
            str(int(row["rho_rgb_clipped"])),
        ]
        for f in RGB_FIELDS:
            vals += [_fmt(v) for v in row[f]]
        vals += [_fmt(row[f]) for f in SCALAR_FIELDS]
        out.append(",".join(vals))
    return out


def _fmt(v):
    s = f"{v:.{DECIMALS}f}"
    return s[1:] if s.startswith("-") and not s.strip("-0.") else s  # no "-0.000..."


def load_table(
    working_space: str = "lin_rec709", path: str | os.PathLike[str] | None = None
) -> tuple[dict[str, str], dict[str, Any]]:
    """The shipped table as (header dict, columns dict of arrays; ``patch`` a list of str).

    Examples
    --------
    >>> header, cols = load_table("lin_rec709")
    >>> header["regenerate"], len(cols["patch"])
    ('python tools/make_colorshift_table.py', 1080)
    """
    path = Path(path) if path else table_path(working_space)
    header, names, rows = read_headed_csv(path)
    cols: dict[str, Any] = {n: [r[i] for r in rows] for i, n in enumerate(names)}
    for n in names:
        if n != "patch":
            cols[n] = np.array(cols[n], dtype=np.float64)
    return header, cols
