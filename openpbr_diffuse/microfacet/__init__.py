"""The GGX microfacet lobe family: the specular and metal lobes of OpenPBR.

- ``ggx``: the GGX distribution D, Smith masking-shadowing (G1, height-correlated G2),
  visible-normal (Heitz 2018) and NDF sampling of the reflected direction and their pdfs;
- ``fresnel``: exact dielectric Fresnel, specular_weight's modulated index, F82-tint;
- ``tables``: the shipped directional-albedo tables of the dielectric and F82-tint lobes
  (``data/specular_albedo_*.csv``) and their interpolation;
- ``quadrature``: the half-vector quadrature that generates those tables
  (``tools/make_specular_table.py``).

Shading nodes (``openpbr_diffuse.nodes``) compose these lobes; nothing here knows about
nodes.
"""

from . import fresnel, ggx, quadrature, tables

__all__ = ["ggx", "fresnel", "tables", "quadrature"]
