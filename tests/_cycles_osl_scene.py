"""Runs inside a Python that has ``bpy``: renders OSL shaders through Cycles' Script node.

    PYTHON _cycles_osl_scene.py HARNESS.osl SHADER.osl OUT W H MU_O

Each file is compiled by Cycles' own oslc (``_cycles.osl_compile``; exit status 3 when it
fails), loaded in a Script node (CPU, OSL shading) whose first output drives an Emission of
strength 1 on a plane (normal +z) seen by an orthographic camera, 1 sample, box filter, black
world: a pixel is the output's value.  ``HARNESS`` fills a W x H image looking straight down
(pixel (i, j) covers P.x + W/(2H) in [i/H, (i+1)/H), P.y + 1/2 in [j/H, (j+1)/H)); ``SHADER``
a 4 x 4 image seen along wo = (0, -sqrt(1 - MU_O^2), MU_O).  Writes OUT.npz: ``harness``
(H, W, 3), ``shader`` (4, 4, 3) and the Script nodes' output names.
"""

import glob
import math
import os
import sys

import numpy as np


def main(harness, shader, out, width, height, mu_o):
    import bpy  # first: it registers _cycles

    _cycles = __import__("_cycles")

    # the add-on's Script node update imports oslquery, which bpy ships in its own site-packages
    sys.path.extend(
        glob.glob(
            os.path.join(
                os.path.dirname(bpy.utils.system_resource("SCRIPTS")), "python", "lib", "python3*", "site-packages"
            )
        )
    )
    from cycles import osl

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.shading_system = True
    cy.samples = 1
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.resolution_percentage = 100
    scene.world = bpy.data.worlds.new("black")
    scene.world.color = (0.0, 0.0, 0.0)
    results = {}
    for name, path, w, h in (("harness", harness, width, height), ("shader", shader, 4, 4)):
        if not _cycles.osl_compile(path, f"{out}.{name}.oso"):
            sys.exit(3)
        os.remove(f"{out}.{name}.oso")
        for ob in list(scene.objects):
            bpy.data.objects.remove(ob)
        hx = 0.5 * w / h
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata([(-hx, -0.5, 0), (hx, -0.5, 0), (hx, 0.5, 0), (-hx, 0.5, 0)], [], [(0, 1, 2, 3)])
        plane = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(plane)
        material = bpy.data.materials.new(name)
        if material.node_tree is None:
            material.use_nodes = True
        nt = material.node_tree
        nt.nodes.clear()
        script = nt.nodes.new("ShaderNodeScript")
        script.mode = "EXTERNAL"
        script.filepath = path
        if not osl.update_script_node(script, lambda kind, msg: print(kind, msg, file=sys.stderr)):
            sys.exit(3)
        emission = nt.nodes.new("ShaderNodeEmission")
        emission.inputs["Strength"].default_value = 1.0
        output = nt.nodes.new("ShaderNodeOutputMaterial")
        nt.links.new(script.outputs[0], emission.inputs["Color"])
        nt.links.new(emission.outputs[0], output.inputs["Surface"])
        mesh.materials.append(material)
        cam_data = bpy.data.cameras.new(name)
        cam_data.type = "ORTHO"
        camera = bpy.data.objects.new(name, cam_data)
        scene.collection.objects.link(camera)
        scene.camera = camera
        if name == "harness":
            cam_data.ortho_scale = 2 * hx
            camera.location = (0.0, 0.0, 5.0)
        else:  # tilted about x: the camera looks along (0, sin t, -cos t), so wo = (0, -sin t, cos t)
            t = math.acos(mu_o)
            cam_data.ortho_scale = 0.2
            camera.rotation_euler = (t, 0.0, 0.0)
            camera.location = (0.0, -5.0 * math.sin(t), 5.0 * mu_o)
        scene.render.resolution_x, scene.render.resolution_y = w, h
        scene.render.filepath = f"{out}.{name}.exr"
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        pixels = np.empty(len(image.pixels), dtype=np.float32)
        image.pixels.foreach_get(pixels)  # float EXR, linear, RGBA, bottom row first
        bpy.data.images.remove(image)
        os.remove(scene.render.filepath)
        results[name] = pixels.reshape(h, w, 4)[:, :, :3]
        results[name + "_outputs"] = np.array([s.name for s in script.outputs])
    np.savez(out, **results)


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))  # keep tests/ off sys.path (Blender's add-ons)
    sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != here]
    a = sys.argv[1:]
    main(a[0], a[1], a[2], int(a[3]), int(a[4]), float(a[5]))
