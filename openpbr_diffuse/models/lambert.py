"""Lambert: f = rho/pi, E = rho."""

from .._jit import INV_PI, kernel


@kernel
def lambert_terms() -> float:
    """Channel-independent factor g of f = rho * g (``g = 1/pi``)."""
    return INV_PI


@kernel
def lambert_albedo() -> float:
    """E / rho = 1 (directional and average)."""
    return 1.0
