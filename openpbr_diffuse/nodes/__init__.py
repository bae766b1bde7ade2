"""Shading nodes: MaterialX ``oren_nayar_diffuse_bsdf`` and OpenPBR Surface.

- ``OrenNayarDiffuseBSDF``: MaterialX ``ND_oren_nayar_diffuse_bsdf`` (QON or EON).
- ``OpenPBRSurface``: OpenPBR Surface 1.1 as a mixture of lobes around the diffuse lobe
  (EON diffuse, GGX specular and F82-tint metal, coat, Zeltner sheen fuzz, transmission,
  subsurface) with albedo scaling and albedo-based lobe selection, compiled: the lobes
  (``_surface_kernels``), their block passes (``_surface_passes``) and one driver per verb
  (``_surface_drivers``).

Both read their interface (input names, types, defaults, ranges) from the MaterialX data
library (``materialx_defs``) and share the verbs ``eval(wi, wo)``, ``albedo(wo)``,
``sample(wo, u) -> (wi, pdf)`` and ``pdf(wo, wi)``.  Modules: ``frame`` (shading frames);
the GGX lobes they compose live in ``openpbr_diffuse.microfacet``.
"""

from .materialx_defs import nodedef_inputs
from .openpbr_surface import IgnoredInputWarning, Lobe, OpenPBRSurface
from .oren_nayar import OrenNayarDiffuseBSDF

__all__ = ["OrenNayarDiffuseBSDF", "OpenPBRSurface", "Lobe", "IgnoredInputWarning", "nodedef_inputs"]
