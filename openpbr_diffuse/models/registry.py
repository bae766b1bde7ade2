"""The table of lobe models: names, parameter domains and how each depends on rho.

Every model is written f = rho g + m(rho) h with g, h independent of rho:

- ``MIX_LINEAR``: m = 0 (Lambert, QON family, FON, Gotanda)
- ``MIX_RHO2``: m = rho^2 (Fujii QON's and full Oren-Nayar's interreflection term)
- ``MIX_RHO_MS``: m = rho_ms(rho) of EON Eq. 18

so an albedo table of g and h at rho = 1 gives the albedo at any rho exactly.
"""

import math
from dataclasses import dataclass

from .._arrays import COLOR_MODES  # noqa: F401  (public name, defined with its check)

MIX_LINEAR, MIX_RHO2, MIX_RHO_MS = 0, 1, 2


@dataclass(frozen=True)
class ModelInfo:
    name: str
    id: int
    roughness_name: str  # "sigma" (radians) or "r" (weight in [0, 1])
    roughness_max: float
    mix: int
    closed_form_albedo: bool
    energy_conserving: bool  # albedo <= rho for every rho <= 1, mu, roughness (strictly)
    description: str


_HALF_PI = 0.5 * math.pi

_MODELS = (
    ("lambert", "r", math.inf, MIX_LINEAR, True, True, "Lambert, f = rho/pi (roughness ignored)"),
    ("qon", "sigma", _HALF_PI, MIX_LINEAR, True, False, "qualitative Oren-Nayar (Eq. 1-4)"),
    ("qon_footnote", "sigma", _HALF_PI, MIX_LINEAR, True, False, "QON with 0.57 in A (Oren-Nayar footnote)"),
    ("qon_van_ouwerkerk", "sigma", _HALF_PI, MIX_LINEAR, True, False, "QON, van Ouwerkerk's dot-product rewrite"),
    ("qon_fujii", "sigma", _HALF_PI, MIX_RHO2, True, False, "Fujii 2013 QON with interreflection tint"),
    ("fon", "r", 1.0, MIX_LINEAR, True, True, "Fujii Oren-Nayar (Eq. 10-15)"),
    ("full_on", "sigma", _HALF_PI, MIX_RHO2, False, False, "full Oren-Nayar with interreflection"),
    ("gotanda", "sigma", _HALF_PI, MIX_LINEAR, True, False, "Gotanda 2012 improved Oren-Nayar (Eq. 25)"),
    ("eon", "r", 1.0, MIX_RHO_MS, True, True, "energy-preserving Oren-Nayar, exact E_F (Eq. 16-20)"),
    ("eon_approx", "r", 1.0, MIX_RHO_MS, True, False, "EON with the Eq. 14 fit of E_F in f_ms"),
)

INFO = {m[0]: ModelInfo(m[0], i, *m[1:]) for i, m in enumerate(_MODELS)}

#: The public tuple of model names.
MODELS = tuple(INFO)


def model_info(model: object) -> ModelInfo:
    """Look a model up by name; ValueError/TypeError naming ``model`` otherwise."""
    if not isinstance(model, str):
        raise TypeError(f"model must be a string, one of {', '.join(MODELS)}; got {type(model).__name__}")
    try:
        return INFO[model]
    except KeyError:
        raise ValueError(f"model: unknown model {model!r}; expected one of {', '.join(MODELS)}") from None
