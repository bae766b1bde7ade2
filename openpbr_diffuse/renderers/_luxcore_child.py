"""Child process: build a chart scene with pyluxcore's API and render it (PATHCPU).

    python _luxcore_child.py SCENE_DIR OUT.npy SAMPLES

Run by :mod:`openpbr_diffuse.renderers.luxcore` under the time limit of user code.  Reads
``chart.json`` (tiles' world corners and normals, camera, light), defines one inline quad
mesh and one ``roughmatte`` material per tile, LuxCore's delta directional light
(``sharpdistant``) of gain E, an orthographic camera over the chart's extent, a box-free
film (no pixel filter) with a linear image pipeline (``TONEMAP_LINEAR``, scale 1), and
saves the film's ``RGB`` output (linear radiance, rows top-down) as a float32 ``.npy``.
pyluxcore bundles its own OpenImageIO, so the EXR is written by the parent.  The last line
on stdout is ``{"version": ...}``.
"""

import json
import math
import os
import sys
import time

import numpy as np


def main(scene_dir: str, out: str, samples: int) -> None:
    import pyluxcore as lx  # type: ignore[import-untyped]

    chart = json.loads(open(os.path.join(scene_dir, "chart.json")).read())
    lx.Init(lambda _msg: None)
    scene = lx.Scene()
    props = lx.Properties()

    def put(key, value):
        props.Set(lx.Property(key, value))

    cam = chart["camera"]
    pos, d, (ew, eh) = cam["position"], cam["direction"], cam["extent"]
    put("scene.camera.type", "orthographic")
    put("scene.camera.lookat.orig", [float(x) for x in pos])
    put("scene.camera.lookat.target", [float(pos[i] + d[i]) for i in range(3)])
    put("scene.camera.up", [float(x) for x in cam["up"]])
    put("scene.camera.screenwindow", [-ew / 2, ew / 2, -eh / 2, eh / 2])
    light = chart["light"]
    # LuxCore's direction is the one the light travels: away from the light
    put("scene.lights.sun.type", "sharpdistant")
    put("scene.lights.sun.direction", [-float(x) for x in light["direction"]])
    put("scene.lights.sun.color", [1.0, 1.0, 1.0])
    put("scene.lights.sun.gain", [float(light["irradiance"])] * 3)
    for t in chart["tiles"]:
        mat, shape = "M_" + t["id"], "S_" + t["id"]
        put(f"scene.materials.{mat}.type", "roughmatte")
        put(f"scene.materials.{mat}.kd", [float(x) for x in t["rho"]])
        # OpenPBR's r in [0, 1] -> Oren-Nayar's sigma in [0, pi/2] (radians: LuxCore's unit)
        put(f"scene.materials.{mat}.sigma", float(t["roughness"]) * math.pi / 2)
        scene.DefineMesh(
            shape,
            [tuple(float(x) for x in p) for p in t["corners"]],
            [(0, 1, 2), (0, 2, 3)],
            [tuple(float(x) for x in t["normal"])] * 4,
            None,
            None,
            None,
        )
        put(f"scene.objects.{t['id']}.shape", shape)
        put(f"scene.objects.{t['id']}.material", mat)
    scene.Parse(props)
    width, height = int(chart["width"]), int(chart["height"])
    cfg = lx.Properties()
    for key, value in {
        "renderengine.type": "PATHCPU",
        "sampler.type": "SOBOL",
        "film.width": width,
        "film.height": height,
        "film.filter.type": "NONE",
        "batch.haltspp": samples,
        "path.pathdepth.total": 3,
        "film.imagepipelines.0.0.type": "TONEMAP_LINEAR",
        "film.imagepipelines.0.0.scale": 1.0,
        "film.outputs.0.type": "RGB",
        "film.outputs.0.filename": "unused.exr",
        "native.threads.count": 2,
    }.items():
        cfg.Set(lx.Property(key, value))
    session = lx.RenderSession(lx.RenderConfig(cfg, scene))
    session.Start()
    while not session.HasDone():
        time.sleep(0.05)
        session.UpdateStats()
    session.Stop()
    buf = np.zeros((height, width, 3), np.float32)
    session.GetFilm().GetOutputFloat(lx.FilmOutputType.RGB, buf)
    np.save(out, np.ascontiguousarray(buf[::-1]))  # the film's rows are bottom-up
    print(json.dumps({"version": lx.Version()}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]))
    sys.stdout.flush()
    os._exit(0)  # pyluxcore's shutdown frees a pointer twice (free(): invalid pointer)
