"""colour-science, imported on first use, without its plotting sub-package.

Both the material readers (colour-space conversions) and the spectral features use
colour-science; this module is below both of them in the import layering.
"""

from __future__ import annotations

import sys
import types

import numpy as np


def _colour():
    """colour-science, imported on first use (1-3 s; only the spectral features need it)."""
    colour = sys.modules.get("colour")
    return colour if colour is not None else _import_colour_without_plotting()


def _import_colour_without_plotting():
    # colour-science 0.4.x runs ``from colour import plotting`` in ``colour/__init__.py``,
    # which imports matplotlib.pyplot when matplotlib is installed: more than half of
    # ``import colour`` (measured 0.8 of 1.3 s idle, 4 of 7 s loaded).  Nothing here plots,
    # so a placeholder stands in for ``colour.plotting`` during the import and is removed
    # afterwards: a later ``import colour.plotting`` loads the real sub-package.
    # colour-science also sets np.set_printoptions(legacy="1.13") on import: a library
    # imported lazily should not change its caller's NumPy print options, so they are restored.
    placeholder = types.ModuleType("colour.plotting")
    sys.modules["colour.plotting"] = placeholder
    print_options = np.get_printoptions()
    try:
        import colour
    except ImportError as exc:
        raise ImportError(
            f"the spectral features need colour-science ({exc}): pip install 'colour-science>=0.4.4'"
        ) from exc
    finally:
        np.set_printoptions(**print_options)
        if sys.modules.get("colour.plotting") is placeholder:
            del sys.modules["colour.plotting"]
    module = getattr(colour, "_module", colour)  # colour wraps itself in a ModuleAPI proxy
    if getattr(module, "plotting", None) is placeholder:
        delattr(module, "plotting")
    return colour
