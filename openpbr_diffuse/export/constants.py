"""The constants of the exported code, read from the modules that compute with them.

Every value is looked up when an export is made (module attributes, not copies), so a
change to the package's formulas changes every export.
"""

from __future__ import annotations

import numpy as np

from .. import _jit
from ..models import fon
from ..sampling import ltc, mis, simple

PRECISIONS = ("float", "double")


def constants(precision: str = "float") -> dict[str, float]:
    """Name -> value of every ``{KEY}`` of the neutral source, for ``precision``.

    Examples
    --------
    >>> c = constants()
    >>> round(c["C1"], 12), c["LTC_A0"], c["PU0"]
    (0.287793409211, 0.303392, 0.162925)
    >>> constants("double")["U_MAX"] == 1.0 - 2.0**-53
    True
    """
    if precision not in PRECISIONS:
        raise ValueError(f"precision: expected float or double, got {precision!r}")
    dtype = np.float32 if precision == "float" else np.float64
    values = {
        "PI": _jit.PI,
        "INV_PI": _jit.INV_PI,
        "TWO_PI": 2.0 * _jit.PI,
        "INV_2PI": simple.INV_2PI,
        "C1": fon.C1,
        "C2": fon.C2,
        "G1": fon.G1,
        "G2": fon.G2,
        "G3": fon.G3,
        "G4": fon.G4,
        "C2_APPROX": fon.C2_APPROX,
        "EPS": _jit.EPS,
        "MU_FLOOR": _jit.MU_FLOOR,
        "TINY": float(np.finfo(dtype).tiny),
        "U_MAX": float(np.nextafter(dtype(1.0), dtype(0.0))),
    }
    for key, fit in (
        ("LTC_A", ltc.LTC_FIT_A),
        ("LTC_B", ltc.LTC_FIT_B),
        ("LTC_C", ltc.LTC_FIT_C),
        ("LTC_D", ltc.LTC_FIT_D),
    ):
        values.update({f"{key}{k}": float(v) for k, v in enumerate(fit)})
    values.update({f"PU{k}": float(v) for k, v in enumerate(mis.UNIFORM_FIT)})
    return values


def literal(value: float) -> str:
    """A decimal literal that reads back as ``value`` in float64 (and so rounds correctly to float32).

    Examples
    --------
    >>> literal(0.5), literal(1e-07), literal(3.0)
    ('0.5', '1e-07', '3.0')
    """
    text = repr(float(value))
    if not np.isfinite(value):
        raise ValueError(f"value: expected a finite constant, got {text}")
    return text


__all__ = ["PRECISIONS", "constants", "literal"]
