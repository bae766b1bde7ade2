"""Reference albedos: hemisphere quadrature, the shipped reference tables, LUT export.

- ``quadrature``: ``hemisphere_albedo`` / ``hemisphere_average_albedo`` integrate any
  vectorised BRDF callable f(wi, wo) over the hemisphere (Gauss-Legendre panels split at
  the kinks of the Oren-Nayar family), with an error estimate.
- ``generate``: the reference tables of every model (``openpbr_diffuse/data/albedo_*.csv``),
  computed with that quadrature from ``evaluate`` (``tools/make_tables.py``);
- ``tables``: ``reference_albedo`` and ``reference_average_albedo``, which interpolate them
  (the lookup itself is ``openpbr_diffuse.models.tables``, below the models' API).
- ``export``: 32-bit float EXR lookup textures for real-time engines (``export_lut``).
"""

from .quadrature import hemisphere_albedo, hemisphere_average_albedo
from .tables import AlbedoTable, load_table, reference_albedo, reference_average_albedo, table_albedo

__all__ = [
    "hemisphere_albedo",
    "hemisphere_average_albedo",
    "reference_albedo",
    "reference_average_albedo",
    "table_albedo",
    "load_table",
    "AlbedoTable",
]
