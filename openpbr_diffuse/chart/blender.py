'''The chart scene as a Blender script: builds it in bpy and renders a linear EXR (Cycles, EEVEE or Hydra Storm).

The script reads the chart.json beside it; run it with Blender or a Python with ``bpy``::

    blender -b -P render_blender.py -- OUT.exr [SAMPLES] [ENGINE]
    python render_blender.py OUT.exr [SAMPLES] [ENGINE]          # bpy as a module

ENGINE is ``CYCLES`` (the default), ``EEVEE`` (samples = its render samples; needs an
OpenGL context: EGL without a display) or ``HYDRA_STORM`` (the hydra_storm add-on).

Principled BSDF per tile: Base Color = rho, Diffuse Roughness = the tile's roughness,
Specular IOR Level 0, Metallic 0, Coat 0, Sheen 0.  A Sun of strength E (W/m^2, angle 0),
a point light of power 4 pi I (W), or a white world of strength L (the furnace).  Colour
management: view transform Standard, look None, exposure 0, gamma 1; film not
transparent; the world black (not in the furnace); no denoiser, no clamping; a box pixel
filter one pixel wide; a float EXR.

Example
-------
>>> "Diffuse Roughness" in SCRIPT and "Standard" in SCRIPT
True
'''

from __future__ import annotations

#: Samples per pixel by default: the light is a delta (sun or point) and the tiles see no
#: sky, so the direct light needs one sample; a few more average the pixel filter.
DEFAULT_SAMPLES = 16

SCRIPT = r'''"""Build and render an openpbr-diffuse conformance chart scene with Blender (Cycles by default).

    blender -b -P render_blender.py -- OUT.exr [SAMPLES] [ENGINE]
    python render_blender.py OUT.exr [SAMPLES] [ENGINE]

ENGINE: CYCLES (default), EEVEE (SAMPLES = its render samples) or HYDRA_STORM.

Reads chart.json from this script's folder (schema openpbr-diffuse-chart/1).
"""
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# this folder first on sys.path could shadow Blender's own modules
sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != HERE]

import bpy  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
if not argv:
    sys.exit("usage: render_blender.py OUT.exr [SAMPLES] [CYCLES|EEVEE|HYDRA_STORM]")
OUT = os.path.abspath(argv[0])
SAMPLES = int(argv[1]) if len(argv) > 1 else __SAMPLES__
ENGINE = argv[2].upper() if len(argv) > 2 else "CYCLES"
if ENGINE not in ("CYCLES", "EEVEE", "HYDRA_STORM"):
    sys.exit(f"ENGINE: expected CYCLES, EEVEE or HYDRA_STORM, got {argv[2]!r}")
if os.path.exists(OUT):
    sys.exit(f"{OUT} exists: not overwritten")
chart = json.load(open(os.path.join(HERE, "chart.json")))

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
if ENGINE == "EEVEE":  # "BLENDER_EEVEE_NEXT" in Blender 4.2 to 4.4
    names = bpy.types.RenderSettings.bl_rna.properties["engine"].enum_items.keys()
    scene.render.engine = "BLENDER_EEVEE_NEXT" if "BLENDER_EEVEE_NEXT" in names else "BLENDER_EEVEE"
    scene.eevee.taa_render_samples = SAMPLES
elif ENGINE == "HYDRA_STORM":
    bpy.ops.preferences.addon_enable(module="hydra_storm")
    scene.render.engine = "HYDRA_STORM"
cy = scene.cycles
cy.device = "CPU"
cy.samples = SAMPLES
cy.use_adaptive_sampling = False
cy.use_denoising = False
cy.pixel_filter_type = "BOX"
cy.filter_width = 1.0
cy.sample_clamp_direct = 0.0
cy.sample_clamp_indirect = 0.0
cy.max_bounces = 4
scene.render.resolution_x = chart["width"]
scene.render.resolution_y = chart["height"]
scene.render.resolution_percentage = 100
scene.render.film_transparent = False
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.view_settings.gamma = 1.0
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"

light = chart["light"]
world = bpy.data.worlds.new("chart_world")
scene.world = world
world.use_nodes = True
bg = world.node_tree.nodes["Background"]
bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
bg.inputs["Strength"].default_value = float(light["radiance"]) if light["kind"] == "furnace" else 0.0

cam = chart["camera"]
cam_data = bpy.data.cameras.new("chart_camera")
cam_data.type = "ORTHO"
cam_data.ortho_scale = max(cam["extent"])
cam_data.sensor_fit = "AUTO"
cam_data.clip_start = cam["near"]
cam_data.clip_end = cam["far"]
camera = bpy.data.objects.new("chart_camera", cam_data)
camera.location = cam["position"]  # Blender's camera looks down -z, up +y: as the chart's
scene.collection.objects.link(camera)
scene.camera = camera

if light["kind"] == "distant":
    data = bpy.data.lights.new("chart_sun", "SUN")
    data.energy = float(light["irradiance"])
    data.angle = 0.0
    sun = bpy.data.objects.new("chart_sun", data)
    sun.rotation_euler = (0.0, math.radians(chart.get("light_view_angle_deg", 0.0)), 0.0)
    scene.collection.objects.link(sun)
elif light["kind"] == "point":
    data = bpy.data.lights.new("chart_point", "POINT")
    data.energy = 4.0 * math.pi * float(light["intensity"])
    data.shadow_soft_size = 0.0
    lamp = bpy.data.objects.new("chart_point", data)
    lamp.location = light["position"]
    scene.collection.objects.link(lamp)

for tile in chart["tiles"]:
    mesh = bpy.data.meshes.new(tile["id"])
    mesh.from_pydata([tuple(p) for p in tile["corners"]], [], [(0, 1, 2, 3)])
    mesh.update()
    obj = bpy.data.objects.new(tile["id"], mesh)
    scene.collection.objects.link(obj)
    mat = bpy.data.materials.new("M_" + tile["id"])
    mat.use_nodes = True
    p = mat.node_tree.nodes["Principled BSDF"]
    p.inputs["Base Color"].default_value = (*tile["rho"], 1.0)
    p.inputs["Diffuse Roughness"].default_value = tile["roughness"]
    p.inputs["Metallic"].default_value = 0.0
    p.inputs["Specular IOR Level"].default_value = 0.0
    p.inputs["Coat Weight"].default_value = 0.0
    p.inputs["Sheen Weight"].default_value = 0.0
    mesh.materials.append(mat)

scene.render.filepath = OUT
bpy.ops.render.render(write_still=True)
print("openpbr-diffuse chart: rendered", OUT, "with Blender", bpy.app.version_string, scene.render.engine)
'''.replace("__SAMPLES__", str(DEFAULT_SAMPLES))


def blender_script() -> str:
    """The text of ``render_blender.py`` (the same for every scene: it reads chart.json).

    >>> "Build and render" in blender_script()
    True
    """
    return SCRIPT


__all__ = ["blender_script", "SCRIPT", "DEFAULT_SAMPLES"]
