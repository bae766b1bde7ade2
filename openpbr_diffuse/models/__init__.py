"""Lobe models of the Oren-Nayar family and EON, each in its own module.

``registry`` names them; ``api`` holds the public verbs; ``_kernels`` the compiled batch
drivers that call the per-model formula functions.
"""

from .api import average_albedo, directional_albedo, evaluate
from .registry import COLOR_MODES, MODELS, model_info

__all__ = ["MODELS", "COLOR_MODES", "evaluate", "directional_albedo", "average_albedo", "model_info"]
