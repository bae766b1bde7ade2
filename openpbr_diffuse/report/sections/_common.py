"""Helpers several report sections share: the roughness range they sweep, random directions,
the layout of their rows of panels, and the copying of a shipped figure into the report."""

from __future__ import annotations

import math
import shutil
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ...result import Result
from .._plot import save
from ..model import CheckTable, Context

#: The layout of a row of panels under a ``suptitle`` (``Figure.subplots_adjust`` arguments).
PANELS: dict[str, float] = {"left": 0.07, "right": 0.98, "bottom": 0.15, "top": 0.85, "wspace": 0.28, "hspace": 0.5}


def roughness_max(info: Any) -> float:
    """The largest roughness a section sweeps for a model: its range, capped at r = 1 / sigma = pi/2.

    >>> from openpbr_diffuse.models.registry import INFO
    >>> roughness_max(INFO["lambert"]), roughness_max(INFO["qon"]) == 0.5 * math.pi
    (1.0, True)
    """
    return min(info.roughness_max, 1.0 if info.roughness_name == "r" else 0.5 * math.pi)


def random_directions(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` random unit vectors above the surface: cos theta uniform in [0.01, 1], then phi in [0, 2 pi).

    >>> d = random_directions(np.random.default_rng(0), 4)
    >>> d.shape, bool(np.allclose(np.linalg.norm(d, axis=-1), 1.0)), bool((d[:, 2] >= 0.01).all())
    ((4, 3), True, True)
    """
    z = rng.uniform(0.01, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def label_panels(axes: Iterable[Any], xlabel: str, legend_size: float) -> None:
    """Give every axis of ``axes`` the x label ``xlabel``, a light grid and a legend.

    >>> from openpbr_diffuse.report._plot import pyplot
    >>> plt = pyplot()
    >>> fig, axes = plt.subplots(1, 2)
    >>> for ax in axes:
    ...     _ = ax.plot([0, 1], [0, 1], label="y = x")
    >>> label_panels(axes, "x", 7)
    >>> [ax.get_xlabel() for ax in axes], axes[1].get_legend() is not None
    (['x', 'x'], True)
    >>> plt.close(fig)
    """
    for ax in axes:
        ax.set_xlabel(xlabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=legend_size)


def save_panels(fig: Any, ctx: Context, name: str) -> str:
    """Lay ``fig`` out as a row of panels (:data:`PANELS`), write it to ``ctx.image_dir / name``; the name.

    >>> import tempfile
    >>> from openpbr_diffuse.report._plot import pyplot
    >>> fig, ax = pyplot().subplots(1, 2)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     name = save_panels(fig, Context(Path(d)), "panels.png")
    ...     name, (Path(d) / name).is_file()
    ('panels.png', True)
    """
    fig.subplots_adjust(**PANELS)
    return save(fig, ctx, name)


def within_errors(table: CheckTable, title: str, z: float, threshold: float, reference: str, detail: str) -> Result:
    """Check ``title`` of ``table``: a live Monte Carlo estimate ``z`` standard errors off its reference.

    >>> t = CheckTable.declared("simulation")
    >>> c = within_errors(t, t.ids[0], 1.3, 4.5, "the shipped table", "live vs shipped")
    >>> c.passed, c.unit
    (True, 'standard errors')
    """
    return table.check(
        title, measured=float(z), threshold=threshold, unit="standard errors", reference=reference, detail=detail
    )


def copy_figure(shipped: Path, ctx: Context) -> Path:
    """Copy a figure shipped with the package into ``ctx.image_dir`` (same file name); the copy.

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as src, tempfile.TemporaryDirectory() as out:
    ...     _ = (Path(src) / "f.png").write_bytes(b"png")
    ...     copy_figure(Path(src) / "f.png", Context(Path(out))).read_bytes()
    b'png'
    """
    return Path(shutil.copy(shipped, Path(ctx.image_dir) / shipped.name))


__all__ = [
    "PANELS",
    "copy_figure",
    "label_panels",
    "random_directions",
    "roughness_max",
    "save_panels",
    "within_errors",
]
