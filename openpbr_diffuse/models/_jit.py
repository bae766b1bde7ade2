"""Kernel compilation settings shared by every model.

Each formula of the paper is written once, as a scalar function compiled by numba
(``kernel``); the batch drivers in ``_kernels.py`` loop over arrays in parallel and call
them.  The same functions are what the tests verify: there is no second NumPy copy.

``fastmath`` is restricted to flags that keep IEEE semantics for NaN/Inf (the input checks
and the ``max(eps, .)`` guards of Listing 1 rely on them) but allow contraction and
reciprocal approximations that do not change results beyond rounding.
"""
import math

import numba

FASTMATH = {"contract", "arcp", "nsz", "afn"}

#: Decorator for scalar formula functions (inlined into the batch drivers).
kernel = numba.njit(cache=True, fastmath=FASTMATH, inline="always")

PI = math.pi
INV_PI = 1.0 / math.pi
EPS = 1e-7  # the epsilon of Listing 1 (f_ms guards)
