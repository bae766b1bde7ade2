"""The chart scene as USD: UsdGeomMesh tiles, MaterialX OpenPBR materials, UsdLux, a camera.

Every tile is a quad (its four world corners from chart.json) bound to a material whose
surface is ``ND_open_pbr_surface_surfaceshader`` with ``base_color`` = rho (linear
Rec. 709), ``base_diffuse_roughness`` = the tile's roughness and ``specular_weight`` = 0
(the diffuse lobe alone).  The light: a UsdLuxDistantLight (angle 0, intensity = the
irradiance E), a UsdLuxSphereLight (radius 0, treatAsPoint; intensity I), or a
UsdLuxDomeLight (white, intensity = L).  The camera is orthographic, its apertures in
tenths of a world unit (the USD convention).

Example
-------
>>> from openpbr_diffuse.chart.layout import build_scene
>>> text = usda(build_scene(35.0, resolution=256))
>>> "ND_open_pbr_surface_surfaceshader" in text, 'token projection = "orthographic"' in text
(True, True)
"""

from __future__ import annotations

from typing import Any


def _f(x: float) -> str:
    return f"{x:.9g}"


def _v(v) -> str:
    return "(" + ", ".join(_f(x) for x in v) + ")"


def _light(light: dict[str, Any], gamma: float) -> list[str]:
    if light["kind"] == "distant":
        return [
            '    def DistantLight "Light"',
            "    {",
            "        float inputs:angle = 0",
            f"        float inputs:intensity = {_f(light['irradiance'])}",
            "        float inputs:exposure = 0",
            "        color3f inputs:color = (1, 1, 1)",
            f"        float3 xformOp:rotateXYZ = (0, {_f(gamma)}, 0)",
            '        uniform token[] xformOpOrder = ["xformOp:rotateXYZ"]',
            "    }",
        ]
    if light["kind"] == "point":
        return [
            '    def SphereLight "Light"',
            "    {",
            "        float inputs:radius = 0",
            "        bool treatAsPoint = true",
            f"        float inputs:intensity = {_f(light['intensity'])}",
            "        float inputs:exposure = 0",
            "        color3f inputs:color = (1, 1, 1)",
            f"        double3 xformOp:translate = {_v(light['position'])}",
            '        uniform token[] xformOpOrder = ["xformOp:translate"]',
            "    }",
        ]
    return [
        '    def DomeLight "Light"',
        "    {",
        f"        float inputs:intensity = {_f(light['radiance'])}",
        "        float inputs:exposure = 0",
        "        color3f inputs:color = (1, 1, 1)",
        "    }",
    ]


def usda(scene: dict[str, Any]) -> str:
    """The ``.usda`` text of a chart scene (a chart.json document).

    >>> from openpbr_diffuse.chart.layout import build_scene
    >>> 'def DomeLight "Light"' in usda(build_scene(0.0, "furnace", 256))
    True
    """
    cam = scene["camera"]
    w, h = cam["extent"]
    lines = [
        "#usda 1.0",
        "(",
        f'    doc = "openpbr-diffuse conformance chart {scene["id"]} ({scene["schema"]}); see chart.json"',
        '    defaultPrim = "Chart"',
        "    metersPerUnit = 1",
        '    upAxis = "Y"',
        ")",
        "",
        'def Xform "Chart"',
        "{",
        '    def Camera "Camera"',
        "    {",
        '        token projection = "orthographic"',
        f"        float horizontalAperture = {_f(10 * w)}",
        f"        float verticalAperture = {_f(10 * h)}",
        f"        float2 clippingRange = ({_f(cam['near'])}, {_f(cam['far'])})",
        f"        double3 xformOp:translate = {_v(cam['position'])}",
        '        uniform token[] xformOpOrder = ["xformOp:translate"]',
        "    }",
        "",
    ]
    gamma = float(scene.get("light_view_angle_deg", 0.0))
    lines += _light(scene["light"], gamma)
    lines += ["", '    def Scope "Materials"', "    {"]
    for t in scene["tiles"]:
        name = f"M_{t['id']}"
        path = f"/Chart/Materials/{name}"
        lines += [
            f'        def Material "{name}"',
            "        {",
            f"            token outputs:mtlx:surface.connect = <{path}/Surface.outputs:out>",
            '            def Shader "Surface"',
            "            {",
            '                uniform token info:id = "ND_open_pbr_surface_surfaceshader"',
            "                float inputs:base_weight = 1",
            f"                color3f inputs:base_color = {_v(t['rho'])}",
            f"                float inputs:base_diffuse_roughness = {_f(t['roughness'])}",
            "                float inputs:specular_weight = 0",
            "                float inputs:coat_weight = 0",
            "                token outputs:out",
            "            }",
            "        }",
        ]
    lines += ["    }", "", '    def Scope "Tiles"', "    {"]
    for t in scene["tiles"]:
        n = t["normal"]
        pts = ", ".join(_v(p) for p in t["corners"])
        lines += [
            f'        def Mesh "{t["id"]}" (',
            '            prepend apiSchemas = ["MaterialBindingAPI"]',
            "        )",
            "        {",
            f"            point3f[] points = [{pts}]",
            "            int[] faceVertexCounts = [4]",
            "            int[] faceVertexIndices = [0, 1, 2, 3]",
            f"            normal3f[] normals = [{', '.join([_v(n)] * 4)}] (",
            '                interpolation = "vertex"',
            "            )",
            '            uniform token subdivisionScheme = "none"',
            "            uniform bool doubleSided = 0",
            f"            rel material:binding = </Chart/Materials/M_{t['id']}>",
            "        }",
        ]
    lines += ["    }", "}", ""]
    return "\n".join(lines)


__all__ = ["usda"]
