"""The chart scene's materials as a MaterialX document: one ``open_pbr_surface`` per tile.

MaterialX describes materials, not geometry: its viewers (MaterialXView, the render test
suite) take the geometry separately -- assign material ``M_<tile id>`` to the tile's quad
(its corners are in chart.json) or render the scene from the USD file of the chart, which
binds the same materials.

Example
-------
>>> from openpbr_diffuse.chart.layout import build_scene
>>> import MaterialX as mx
>>> doc = mx.createDocument()
>>> mx.readFromXmlString(doc, mtlx(build_scene(35.0, resolution=256)))
>>> len(doc.getMaterialNodes())
249
"""

from __future__ import annotations

from typing import Any
from xml.sax.saxutils import quoteattr


def mtlx(scene: dict[str, Any]) -> str:
    """The ``.mtlx`` text of a chart scene's materials (colours in lin_rec709).

    >>> from openpbr_diffuse.chart.layout import build_scene
    >>> mtlx(build_scene(0.0, "furnace", 256)).count("<open_pbr_surface ")
    79
    """
    lines = [
        '<?xml version="1.0"?>',
        f"<!-- openpbr-diffuse conformance chart {scene['id']} ({scene['schema']}): one material per tile; "
        "the geometry (quads) is in chart.json and the chart's USD file -->",
        '<materialx version="1.39" colorspace="lin_rec709">',
    ]
    for t in scene["tiles"]:
        name = f"M_{t['id']}"
        rho = ", ".join(f"{x:.9g}" for x in t["rho"])
        lines += [
            f'  <open_pbr_surface name={quoteattr(name + "_surface")} type="surfaceshader">',
            '    <input name="base_weight" type="float" value="1" />',
            f'    <input name="base_color" type="color3" value="{rho}" />',
            f'    <input name="base_diffuse_roughness" type="float" value="{t["roughness"]:.9g}" />',
            '    <input name="specular_weight" type="float" value="0" />',
            '    <input name="coat_weight" type="float" value="0" />',
            "  </open_pbr_surface>",
            f'  <surfacematerial name={quoteattr(name)} type="material">',
            f'    <input name="surfaceshader" type="surfaceshader" nodename={quoteattr(name + "_surface")} />',
            "  </surfacematerial>",
        ]
    lines += ["</materialx>", ""]
    return "\n".join(lines)


__all__ = ["mtlx"]
