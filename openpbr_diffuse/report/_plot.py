"""Matplotlib helpers for the report sections (Agg backend, imported lazily)."""

from pathlib import Path


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
