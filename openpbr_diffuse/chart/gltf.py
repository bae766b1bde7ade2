"""The chart scene as glTF 2.0 (``.gltf`` JSON + ``.bin``) with KHR_materials_diffuse_roughness.

One mesh per tile (two triangles, flat normals), a material per tile: baseColorFactor =
rho, metallicFactor 0, KHR_materials_diffuse_roughness ``diffuseRoughnessFactor`` = the
tile's roughness, KHR_materials_specular ``specularFactor`` 0 (the diffuse lobe alone).
The light is KHR_lights_punctual: directional (intensity = E lux; it shines along its
node's -z) or point (intensity = I candela).  glTF has no environment light: the furnace
is written without a light (give the renderer a white environment of radiance L).  The
camera is orthographic (xmag, ymag: half the extent).

Example
-------
>>> from openpbr_diffuse.chart.layout import build_scene
>>> doc, blob = gltf(build_scene(35.0, resolution=256))
>>> buffer = doc["buffers"].pop()
>>> doc["asset"].get("version"), len(blob) == buffer.get("byteLength")
('2.0', True)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

EXTENSIONS = ["KHR_materials_diffuse_roughness", "KHR_materials_specular", "KHR_lights_punctual"]


def gltf(scene: dict[str, Any], bin_name: str = "chart.bin") -> tuple[dict[str, Any], bytes]:
    """(glTF JSON document, binary buffer) of a chart scene.

    >>> from openpbr_diffuse.chart.layout import build_scene
    >>> doc, _ = gltf(build_scene(0.0, "furnace", 256))
    >>> "KHR_lights_punctual" in doc.get("extensionsUsed")   # no light in the furnace
    False
    """
    blob = bytearray()
    accessors: list[dict] = []
    views: list[dict] = []
    meshes, materials, nodes = [], [], []

    def add(data: np.ndarray, target: int, ctype: int, kind: str, minmax: bool = False) -> int:
        raw = data.tobytes()
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(raw), "target": target})
        blob.extend(raw)
        blob.extend(b"\0" * (-len(blob) % 4))
        acc = {"bufferView": len(views) - 1, "componentType": ctype, "count": len(data), "type": kind}
        if minmax:
            acc["min"] = [float(x) for x in data.min(axis=0)]
            acc["max"] = [float(x) for x in data.max(axis=0)]
        accessors.append(acc)
        return len(accessors) - 1

    idx = add(np.array([0, 1, 2, 0, 2, 3], "<u2"), 34963, 5123, "SCALAR")
    for t in scene["tiles"]:
        pos = add(np.asarray(t["corners"], "<f4"), 34962, 5126, "VEC3", minmax=True)
        nrm = add(np.tile(np.asarray(t["normal"], "<f4"), (4, 1)), 34962, 5126, "VEC3")
        materials.append(
            {
                "name": f"M_{t['id']}",
                "pbrMetallicRoughness": {
                    "baseColorFactor": [*map(float, t["rho"]), 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 1.0,
                },
                "extensions": {
                    "KHR_materials_diffuse_roughness": {"diffuseRoughnessFactor": float(t["roughness"])},
                    "KHR_materials_specular": {"specularFactor": 0.0},
                },
            }
        )
        meshes.append(
            {
                "name": t["id"],
                "primitives": [
                    {"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": len(materials) - 1}
                ],
            }
        )
        nodes.append({"name": t["id"], "mesh": len(meshes) - 1})
    cam = scene["camera"]
    w, h = cam["extent"]
    nodes.append({"name": "Camera", "camera": 0, "translation": [float(x) for x in cam["position"]]})
    light = scene["light"]
    lights = []
    if light["kind"] == "distant":
        g = math.radians(float(scene.get("light_view_angle_deg", 0.0)))
        lights.append({"type": "directional", "name": "Light", "intensity": float(light["irradiance"])})
        nodes.append(
            {
                "name": "Light",
                "rotation": [0.0, math.sin(g / 2), 0.0, math.cos(g / 2)],
                "extensions": {"KHR_lights_punctual": {"light": 0}},
            }
        )
    elif light["kind"] == "point":
        lights.append({"type": "point", "name": "Light", "intensity": float(light["intensity"])})
        nodes.append(
            {
                "name": "Light",
                "translation": [float(x) for x in light["position"]],
                "extensions": {"KHR_lights_punctual": {"light": 0}},
            }
        )
    doc: dict[str, Any] = {
        "asset": {"version": "2.0", "generator": f"openpbr-diffuse chart ({scene['schema']}, {scene['id']})"},
        "extensionsUsed": EXTENSIONS if lights else EXTENSIONS[:2],
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [
            {
                "type": "orthographic",
                "orthographic": {"xmag": w / 2, "ymag": h / 2, "znear": float(cam["near"]), "zfar": float(cam["far"])},
            }
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": bin_name, "byteLength": len(blob)}],
    }
    if lights:
        doc["extensions"] = {"KHR_lights_punctual": {"lights": lights}}
    return doc, bytes(blob)


__all__ = ["gltf", "EXTENSIONS"]
