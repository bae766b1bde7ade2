"""Importance sampling of the EON lobe (EON paper Section 3.1, Listings 2-4).

``STRATEGIES`` names the samplers of the paper's Fig. 10: "cosine", "uniform", "ltc",
"ltc_nonneg", "cltc" and "eon" (CLTC + uniform, one-sample MIS: the one to use).
``sample(strategy, wo, roughness, u)`` returns (wi, pdf); ``pdf(strategy, wo, wi, roughness)``
the solid-angle density; ``sample_rng`` draws u from a seeded numpy Generator.

Modules: ``simple`` (cosine, uniform), ``ltc`` (LTC fit, frame, (clipped) LTC sampler and
pdf), ``mis`` (the EON MIS sampler), ``_kernels`` (compiled batch drivers), ``api``.
"""

from .api import pdf, sample, sample_rng
from .registry import INFO, STRATEGIES, strategy_info

__all__ = ["STRATEGIES", "sample", "pdf", "sample_rng", "strategy_info", "INFO"]
