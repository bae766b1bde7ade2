"""Material readers: USD stages and MaterialX documents -> Materials on the library's nodes.

``load_materials(path, *, time=None, variants=None, uv=(0.5, 0.5), material=None)`` reads a
``.usda`` / ``.usdc`` / ``.usdz`` stage (usd-core) or a ``.mtlx`` document (MaterialX) and
returns a list of ``Material`` (resolved parameters with provenance, the library node).
``BUNDLED_MATERIALS`` is the folder of the project's own material library.
"""

from .api import BUNDLED_MATERIALS, MATERIAL_SUFFIXES, find_material_files, load_materials
from .colorspace import WORKING_SPACE
from .material import Material, Parameter

__all__ = [
    "load_materials",
    "BUNDLED_MATERIALS",
    "Material",
    "Parameter",
    "WORKING_SPACE",
    "MATERIAL_SUFFIXES",
    "find_material_files",
]
