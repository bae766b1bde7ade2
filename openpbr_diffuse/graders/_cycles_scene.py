"""Runs inside a Python that has ``bpy``: renders the rows of a job file with Cycles.

Invoked by :mod:`openpbr_diffuse.graders.cycles` as ``PYTHON _cycles_scene.py JOB.json OUT``
with a Python that has ``bpy`` (it needs nothing else: numpy comes with bpy, the EXR is read
back through Blender's own image loader).  Each row is one render of a large
plane carrying a Diffuse BSDF node (colour rho, roughness r, i.e. Cycles' ``bsdf_oren_nayar``),
seen by an orthographic camera looking down world -z, so every pixel sees the plane along the
same direction wo:

* ``brdf`` rows: the plane is rotated so that its local frame maps wo to +z; a sun lamp of
  angle 0 and strength 1 shines from R wi; the world is black.  Pixel = f cos(theta_i).
* ``albedo`` rows: no lamp; the world is uniform white of strength 1.  Pixel = E(mu_o).

Returns, per row, the mean over the image's pixels and its standard error (pixels are
independent estimates: different sample sequences per pixel).
"""

import json
import os
import sys

import numpy as np


def rotation_to_z(w):
    """A rotation matrix R with R @ w = +z (Rodrigues; the azimuth of the frame is irrelevant
    for an isotropic BRDF, and R keeps the angle between wi and wo)."""
    w = np.asarray(w, dtype=np.float64)
    w = w / np.linalg.norm(w)
    z = np.array([0.0, 0.0, 1.0])
    v = np.cross(w, z)
    c = float(np.dot(w, z))
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K * (1.0 / (1.0 + c))


def look_along(direction):
    """Blender rotation (as a Matrix) whose local +Z axis is ``direction``."""
    from mathutils import Vector

    return Vector(tuple(direction)).to_track_quat("Z", "Y").to_euler()


def main(job_path, out_path):
    import bpy
    from mathutils import Matrix

    job = json.loads(open(job_path).read())
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.max_bounces = 1
    cy.diffuse_bounces = 1
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.seed = int(job.get("seed", 0))
    scene.render.resolution_percentage = 100
    scene.render.threads_mode = "FIXED"
    scene.render.threads = int(job.get("threads", 2))
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.film_transparent = False

    world = bpy.data.worlds.new("grader_world")
    scene.world = world
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]

    mesh = bpy.data.meshes.new("grader_plane")
    half = 0.5
    mesh.from_pydata([(-half, -half, 0), (half, -half, 0), (half, half, 0), (-half, half, 0)], [], [(0, 1, 2, 3)])
    plane = bpy.data.objects.new("grader_plane", mesh)
    scene.collection.objects.link(plane)
    material = bpy.data.materials.new("grader_diffuse")
    material.use_nodes = True
    nt = material.node_tree
    nt.nodes.clear()
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    output = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(diffuse.outputs[0], output.inputs["Surface"])
    mesh.materials.append(material)

    cam_data = bpy.data.cameras.new("grader_camera")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = 1.0
    cam_data.clip_start = 1e-3
    cam_data.clip_end = 1e7
    camera = bpy.data.objects.new("grader_camera", cam_data)
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (0.0, 0.0, 10.0)  # default orientation looks down -z: wo (world) = +z

    sun_data = bpy.data.lights.new("grader_sun", "SUN")
    sun_data.angle = 0.0
    sun_data.energy = 1.0
    sun = bpy.data.objects.new("grader_sun", sun_data)
    scene.collection.objects.link(sun)

    means, errors = [], []
    for k, row in enumerate(job["rows"]):
        rho = row["rho"]
        diffuse.inputs["Color"].default_value = (rho[0], rho[1], rho[2], 1.0)
        diffuse.inputs["Roughness"].default_value = row["roughness"]
        if row["kind"] == "brdf":
            wo, wi = np.array(row["wo"]), np.array(row["wi"])
            res, spp = job["brdf_resolution"], job["brdf_samples"]
            background.inputs["Strength"].default_value = 0.0
            sun.hide_render = False
            R = rotation_to_z(wo)
            sun.rotation_euler = look_along(R @ wi)
        else:
            mu = row["mu"]
            wo = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
            R = rotation_to_z(wo)
            res, spp = job["albedo_resolution"], job["albedo_samples"]
            background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
            background.inputs["Strength"].default_value = 1.0
            sun.hide_render = True
        # the plane, rotated by R and stretched along its tilt so that it fills the frame; the
        # camera sits far enough above it that every pixel's ray meets the plane in front of it
        # (a ray at lateral offset d meets a plane seen at mu_o at depth ~ d / mu_o)
        mu_o = max(float(wo[2]), 1e-3)
        scale = 4.0 / mu_o
        camera.location = (0.0, 0.0, 2.0 / mu_o + 10.0)
        plane.matrix_world = Matrix(
            [list(R[0]) + [0.0], list(R[1]) + [0.0], list(R[2]) + [0.0], [0.0, 0.0, 0.0, 1.0]]
        ) @ Matrix.Diagonal((scale, scale, 1.0, 1.0))
        scene.render.resolution_x = scene.render.resolution_y = int(res)
        cy.samples = int(spp)
        scene.render.filepath = f"{out_path}.{k}.exr"
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        pixels = np.empty(len(image.pixels), dtype=np.float32)
        image.pixels.foreach_get(pixels)  # float EXR, linear, RGBA
        bpy.data.images.remove(image)
        os.remove(scene.render.filepath)
        pixels = pixels.reshape(-1, 4)[:, :3].astype(np.float64)
        means.append(pixels.mean(axis=0))
        errors.append(pixels.std(axis=0, ddof=1) / np.sqrt(pixels.shape[0]) if pixels.shape[0] > 1 else np.zeros(3))
    np.savez(
        out_path,
        mean=np.array(means).reshape(-1, 3),
        stderr=np.array(errors).reshape(-1, 3),
        version=bpy.app.version_string,
    )


if __name__ == "__main__":
    # run as a script, this file's folder is sys.path[0]: its cycles.py would shadow Blender's
    # "cycles" add-on (the render engine would then not register)
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != here]
    main(sys.argv[1], sys.argv[2])
