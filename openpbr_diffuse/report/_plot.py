"""Matplotlib helpers for the report sections (Agg backend, imported lazily)."""

import contextlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

#: The report's figures' settings: titles at a fixed height above the axes (no axis of the
#: report has ticks on top, which is all that matplotlib's automatic title placement looks
#: for, at the price of measuring every tick label at every draw: a tenth of the figures'
#: drawing time).
STYLE: dict[str, Any] = {"axes.titley": 1.0, "axes.titlepad": 6.0}


@contextlib.contextmanager
def style() -> Iterator[None]:
    """The report's matplotlib settings (``STYLE``) for the figures made inside the block,
    restored after it.

    >>> with style():
    ...     import matplotlib
    ...     matplotlib.rcParams["axes.titley"]
    1.0
    """
    import matplotlib

    with matplotlib.rc_context(STYLE):  # type: ignore[arg-type]  # the stub lists each rcParams key as a literal
        yield


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def save(fig, ctx, name, dpi=90):
    """Write ``fig`` to ``ctx.image_dir / name`` (PNG) and close it; return the file name."""
    plt = pyplot()
    path = Path(ctx.image_dir) / name
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return name
