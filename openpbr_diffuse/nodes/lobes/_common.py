"""Formulas more than one lobe reads, and the verbs several lobes declare alike (made from
the lobe's constants: its sampler, its sampler's width, its albedo's colour and scalar)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from ..._jit import block
from ...microfacet import kernels as mf
from .._surface_params import PARAM, LayerState

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions


@block
def norm_or_max(mx: bool, a: float, b: float, c: float) -> float:
    """|(a, b, c)| (RGB length), or its largest component's magnitude when ``mx``."""
    return max(max(abs(a), abs(b)), abs(c)) if mx else math.sqrt(a * a + b * b + c * c)


@block
def metal_albedo(p: NDArray[np.float64], offset: int, c: int, E1: float, E5: float, E6: float, ms: bool) -> float:
    """F82-tint GGX albedo F0 (E1 - E5) + E5 - a E6 (times the multiple-scattering factor)."""
    F0 = p[offset + PARAM.METAL_F0 + c]
    return (F0 * (E1 - E5) + E5 - p[offset + PARAM.METAL_A + c] * E6) * mf.multiscatter(F0, E1, ms)


@block
def unit_albedo(p: NDArray[np.float64], offset: int, c: int) -> float:
    """The colour of a lobe's albedo when the albedo is a scalar (1): its score's constant."""
    return 1.0


# --------------------------------------------------------------------------- declarations
# The verbs that several lobes declare alike, one function each with the lobe's constants.


@block
def base_ggx_pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    """The ``pdf`` of a lobe sampled as the base specular's GGX reflection: ``ggx_pdf``,
    computed once a row (``_surface_passes.ggx_pdf_pass``)."""
    return ggx_pdf


def fixed_sampler(sampler_id: int) -> Callable[[int], int]:
    """A lobe's ``sampler`` that draws with ``sampler_id`` (``_surface_params.S_*``) whatever
    the diffuse model.

    Example
    -------
    >>> from openpbr_diffuse.nodes._surface_params import D_EON, S_GGX
    >>> fixed_sampler(S_GGX)(D_EON) == S_GGX
    True
    """

    @block
    def sampler(dmodel: int) -> int:
        return sampler_id

    return sampler


def on_where_positive(weight: int) -> Callable[[NDArray[np.float64], int], bool]:
    """A lobe's ``is_on``: whether its weight input p[offset + weight] (a ``PARAM`` offset) is
    positive.

    Example
    -------
    >>> import numpy as np
    >>> is_on = on_where_positive(1)
    >>> is_on(np.array([0.0, 0.5]), 0), is_on(np.array([0.5, 0.0]), 0)
    (True, False)
    """

    @block
    def is_on(p: NDArray[np.float64], offset: int) -> bool:
        return p[offset + weight] > 0.0

    return is_on


def sampler_width(width: int, side: float = 1.0) -> Callable[[NDArray[np.float64], int], tuple[float, float]]:
    """A lobe's ``sample_setup``: (p[offset + width], side), ``width`` the offset (``PARAM``) of
    the parameter its sampler reads (GGX alpha, roughness), or -1 for a sampler that reads
    none (0.0); ``side`` -1 for a lobe below the surface.

    Example
    -------
    >>> import numpy as np
    >>> sampler_width(1, -1.0)(np.array([0.5, 0.25]), 0), sampler_width(-1)(np.array([0.5]), 0)
    ((0.25, -1.0), (0.0, 1.0))
    """

    @block
    def sample_setup(p: NDArray[np.float64], offset: int) -> tuple[float, float]:
        if width < 0:
            return 0.0, side
        return p[offset + width], side

    return sample_setup


def separable_albedo(color: int = -1, state: str = "") -> tuple[Callable[..., float], ...]:
    """(``constant_albedo``, ``albedo``, ``score``) of a lobe whose albedo is a colour of the
    material times a scalar of mu_o, E[c] = C[c] s(mu_o): C[c] = p[offset + color + c]
    (``color`` a ``PARAM`` offset; -1: C = 1) and s the row's ``LayerState`` field ``state``
    ("": s = 1).  Its score |K E| is then s |K C|, s times the score's constant.

    Example
    -------
    >>> import numpy as np
    >>> from openpbr_diffuse.nodes._surface_params import LayerState
    >>> st = LayerState(*range(9))
    >>> constant_albedo, albedo, score = separable_albedo(1, "coat")
    >>> p = np.array([0.0, 0.5, 0.25, 0.125])
    >>> constant_albedo(p, 0, 2), albedo(2, p, 0, True, st), score(False, p, 0, 0, 2.0, True, st)
    (0.125, 0.5, 8.0)
    """
    field = LayerState._fields.index(state) if state else -1

    @block
    def constant_albedo(p: NDArray[np.float64], offset: int, c: int) -> float:
        """C[c], the colour of the lobe's albedo: its score's constant."""
        if color < 0:
            return 1.0
        return p[offset + color + c]

    @block
    def albedo(c: int, p: NDArray[np.float64], offset: int, ms: bool, st: LayerState) -> float:
        if field < 0:
            return p[offset + color + c]
        if color < 0:
            return st[field]
        return p[offset + color + c] * st[field]

    @block
    def score(
        mx: bool, p: NDArray[np.float64], offset: int, weight_at: int, constant: float, ms: bool, st: LayerState
    ) -> float:
        if field < 0:
            return constant
        return st[field] * constant

    return constant_albedo, albedo, score
