"""Lambert: f = rho/pi, E = rho."""
from ._jit import INV_PI, kernel


@kernel
def lambert_terms():
    """Channel-independent factor g of f = rho * g (``g = 1/pi``)."""
    return INV_PI
