"""Child process: render a chart scene's MaterialX document with MaterialX's own GLSL renderer.

    python _materialx_child.py SCENE_DIR OUT.npy WORK_DIR

Run by :mod:`openpbr_diffuse.renderers.materialx_render` under the time limit of user code.
``GlslRenderer`` makes its GL context through GLX, so the child starts ``Xvfb`` on a free
display (``-displayfd``) first; the run's supervisor kills it with the child.  Each tile is
one render: the tile's quad (an OBJ written to WORK_DIR from ``chart.json``'s corners and
normal) under the chart's orthographic camera (``Camera.createViewMatrix`` /
``createOrthographicMatrix``) and one ``directional_light`` of intensity E; the tile's
rectangle is copied out of the float frame.  The shader is generated once from the first
tile's ``surfacematerial`` (every tile's material is the same ``open_pbr_surface`` with other
values) and each tile's ``base_color`` and ``base_diffuse_roughness`` are set from the document
as the shader's public uniforms.  No environment light (black maps, indirect lighting off),
no shadow map, linear output (``lin_rec709``, no sRGB encoding).  Rows are written top-down
as a float32 ``.npy``; the last line on stdout is ``{"version": ...}``.
"""

import json
import os
import subprocess
import sys

import numpy as np


def start_xvfb() -> str:
    """Start Xvfb on a free display; the display name (``:N``)."""
    read_fd, write_fd = os.pipe()
    subprocess.Popen(
        ["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "64x64x24", "-nolisten", "tcp"],
        pass_fds=(write_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write_fd)
    with os.fdopen(read_fd) as f:
        number = f.readline().strip()
    if not number:
        raise SystemExit("Xvfb did not start")
    return ":" + number


def write_quad(path: str, tile: dict) -> None:
    with open(path, "w") as f:
        for v in tile["corners"]:
            f.write("v " + " ".join(repr(float(x)) for x in v) + "\n")
        f.write("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n")
        f.write("vn " + " ".join(repr(float(x)) for x in tile["normal"]) + "\n")
        f.write("f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n")


def main(scene_dir: str, out: str, work: str) -> None:
    os.environ["DISPLAY"] = start_xvfb()
    import MaterialX as mx
    import MaterialX.PyMaterialXGenGlsl as mx_gen_glsl  # type: ignore[import-untyped]
    import MaterialX.PyMaterialXGenShader as mx_gen  # type: ignore[import-untyped]
    import MaterialX.PyMaterialXRender as mx_render  # type: ignore[import-untyped]
    import MaterialX.PyMaterialXRenderGlsl as mx_render_glsl  # type: ignore[import-untyped]

    chart = json.loads(open(os.path.join(scene_dir, "chart.json")).read())
    width, height = int(chart["width"]), int(chart["height"])
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, os.path.join(scene_dir, "chart.mtlx"))
    doc.setDataLibrary(lib)

    light = chart["light"]
    light_doc = mx.createDocument()
    light_doc.setDataLibrary(lib)
    sun = light_doc.addNode("directional_light", "sun", "lightshader")
    # MaterialX's direction is the one the light travels: away from the light
    sun.setInputValue("direction", mx.Vector3(*(-float(x) for x in light["direction"])))
    sun.setInputValue("color", mx.Color3(1.0, 1.0, 1.0))
    sun.setInputValue("intensity", float(light["irradiance"]))

    gen = mx_gen_glsl.GlslShaderGenerator.create()
    ctx = mx_gen.GenContext(gen)
    ctx.registerSourceCodeSearchPath(mx.getDefaultDataSearchPath())
    opts = ctx.getOptions()
    # SPECULAR_ENVIRONMENT_NONE generates a shader that does not compile (u_refractionTwoSided
    # undeclared): the environment is importance-sampled, from black maps
    opts.hwSpecularEnvironmentMethod = mx_gen.HwSpecularEnvironmentMethod.SPECULAR_ENVIRONMENT_FIS
    opts.hwShadowMap = False
    opts.hwMaxActiveLightSources = 1
    opts.targetColorSpaceOverride = "lin_rec709"
    opts.hwSrgbEncodeOutput = False
    lights = mx_render.LightHandler.create()
    lights.registerLights(light_doc, [sun], ctx)
    lights.setLightSources([sun])
    lights.setIndirectLighting(False)
    black = mx_render.createUniformImage(4, 4, 3, mx_render.BaseType.FLOAT, mx.Color4(0, 0, 0, 1))
    lights.setEnvRadianceMap(black)
    lights.setEnvIrradianceMap(black)

    renderer = mx_render_glsl.GlslRenderer.create(width, height, mx_render.BaseType.FLOAT)
    renderer.initialize()
    renderer.setImageHandler(mx_render_glsl.GLTextureHandler.create(mx_render.StbImageLoader.create()))
    renderer.setLightHandler(lights)
    cam = chart["camera"]
    pos, d, (ew, eh) = cam["position"], cam["direction"], cam["extent"]
    camera = renderer.getCamera()
    camera.setViewMatrix(
        mx_render.Camera.createViewMatrix(
            mx.Vector3(*pos), mx.Vector3(*(pos[i] + d[i] for i in range(3))), mx.Vector3(*cam["up"])
        )
    )
    camera.setProjectionMatrix(
        mx_render.Camera.createOrthographicMatrix(-ew / 2, ew / 2, -eh / 2, eh / 2, cam["near"], cam["far"])
    )

    image = np.zeros((height, width, 3), np.float32)
    prefix = None
    for tile in chart["tiles"]:
        quad = os.path.join(work, tile["id"] + ".obj")
        write_quad(quad, tile)
        geometry = renderer.getGeometryHandler()
        geometry.clearGeometry()
        if not geometry.loadGeometry(mx.FilePath(quad), False):
            raise SystemExit(f"MaterialX could not load {quad}")
        surface = doc.getNode(f"M_{tile['id']}_surface")
        if prefix is None:
            shader = gen.generate("chart", doc.getNode("M_" + tile["id"]), ctx)
            renderer.createProgram(shader)
            renderer.validateInputs()
            prefix = surface.getName() + "_"
        for name in ("base_color", "base_diffuse_roughness"):
            inp = surface.getInput(name)
            renderer.updateUniform(prefix + name, mx.Value.createValueFromStrings(inp.getValueString(), inp.getType()))
        renderer.render()
        frame = renderer.captureImage(None)
        x0, y0, x1, y1 = tile["rect"]
        for y in range(y0, y1):
            for x in range(x0, x1):
                c = frame.getTexelColor(x, height - 1 - y)  # GL rows are bottom-up
                image[y, x] = (c[0], c[1], c[2])
    np.save(out, image)
    print(json.dumps({"version": mx.__version__}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3])
