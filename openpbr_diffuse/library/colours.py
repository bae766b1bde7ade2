"""The diffuse colour of each material of a file, as plain data (the ``"colours"`` task).

What the colour-shift validation (:func:`openpbr_diffuse.spectral.from_materials`) needs of
a material: its name, file and prim path, shader, whether it is supported, its reader
warnings, the diffuse colour input's name and value (the readers' working space, ACEScg),
its diffuse model and diffuse roughness.  Numbers are kept as ``repr`` strings, so that a
record read back from the cache gives the very same floats (infinities and NaN included).
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Inputs holding the diffuse colour, first found wins (the library node's, then the shader's).
DIFFUSE_COLOR_INPUTS = ("base_color", "color", "diffuseColor")
#: Inputs holding the diffuse roughness, first found wins.
DIFFUSE_ROUGHNESS_INPUTS = ("base_diffuse_roughness", "roughness")


def _inputs(material: Any) -> dict:
    # the library node's inputs after the reader's mapping, else the shader's own
    return getattr(material, "node_inputs", None) or material.parameters


def colour_record(material: Any) -> dict[str, Any]:
    """The colour record of one material read by ``openpbr_diffuse.readers.load_materials``.

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials
    >>> (m,) = load_materials(BUNDLED_MATERIALS / "clay_rough.mtlx")
    >>> r = colour_record(m)
    >>> r["name"], r["key"], len(r["rgb"]), float(r["roughness"])
    ('clay_rough', 'base_color', 3, 1.0)
    """
    inputs = _inputs(material)
    key, rgb, rough = None, None, None
    for k in DIFFUSE_COLOR_INPUTS:
        p = inputs.get(k)
        if p is not None:
            key, rgb = k, [repr(float(v)) for v in np.asarray(p.value, np.float64).reshape(-1)]
            break
    for k in DIFFUSE_ROUGHNESS_INPUTS:
        p = inputs.get(k)
        if p is not None:
            rough = repr(float(np.asarray(p.value, np.float64).reshape(-1)[0]))
            break
    return {
        "name": str(material.name),
        "file": str(material.file),
        "path": str(material.path),
        "shader": str(material.shader_id),
        "supported": bool(material.supported),
        "warnings": [str(w) for w in material.warnings],
        "key": key,
        "rgb": rgb,
        "diffuse_model": getattr(material, "diffuse_model", "") or None,
        "roughness": rough,
    }


__all__ = ["DIFFUSE_COLOR_INPUTS", "DIFFUSE_ROUGHNESS_INPUTS", "colour_record"]
