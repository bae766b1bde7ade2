"""Babylon.js renders the chart's glTF: its glTF loader (@babylonjs/loaders, with
KHR_materials_diffuse_roughness) and ``Engine`` (WebGL2) in headless Chromium.

The page loads ``chart.gltf`` with ``AppendSceneAsync`` as a Babylon.js user would (the default
material, ``PBRMaterial``), takes the glTF's orthographic camera, turns the image processing
off the materials (``imageProcessingConfiguration.applyByPostProcess = true`` with no post
process: linear output, no tone mapping, exposure 1), renders into a float
``RenderTargetTexture`` (``TEXTURETYPE_FLOAT``) and reads it back with ``readPixels``; the
child writes a float EXR.  @babylonjs/core and @babylonjs/loaders are served from the npm
cache with an import map (offline).

Example
-------
>>> "AppendSceneAsync" in PAGE and "TEXTURETYPE_FLOAT" in PAGE
True
"""

from __future__ import annotations

import json
from pathlib import Path

from ..graders.errors import GraderUnavailable
from . import _browser

INSTALL = "npm install --prefix ~/.cache/openpbr-diffuse/npm --ignore-scripts @babylonjs/core @babylonjs/loaders"

PAGE = """<!doctype html>
<html><head><meta charset="utf-8"><title>openpbr-diffuse chart: Babylon.js</title>
<script type="importmap">
{"imports": {"@babylonjs/core/": "/npm/@babylonjs/core/", "@babylonjs/loaders/": "/npm/@babylonjs/loaders/",
 "babylonjs-gltf2interface": "/npm/babylonjs-gltf2interface/babylon.glTF2Interface.js"}}
</script></head><body><canvas id="c"></canvas>
<script type="module">
import { Engine } from "@babylonjs/core/Engines/engine.js";
import { Scene } from "@babylonjs/core/scene.js";
import { Color3, Color4 } from "@babylonjs/core/Maths/math.color.js";
import { Constants } from "@babylonjs/core/Engines/constants.js";
import { RenderTargetTexture } from "@babylonjs/core/Materials/Textures/renderTargetTexture.js";
import { AppendSceneAsync } from "@babylonjs/core/Loading/sceneLoader.js";
import "@babylonjs/core/Loading/loadingScreen.js";
import "@babylonjs/core/Materials/PBR/pbrMaterial.js";
import "@babylonjs/core/Lights/directionalLight.js";
import "@babylonjs/core/Lights/pointLight.js";
import "@babylonjs/core/Cameras/freeCamera.js";
import "@babylonjs/loaders/glTF/2.0/index.js";
import "@babylonjs/loaders/glTF/glTFFileLoader.js";
try {
  const chart = await (await fetch("/scene/chart.json")).json();
  const W = chart.width, H = chart.height;
  const canvas = document.getElementById("c");
  canvas.width = W; canvas.height = H;
  const engine = new Engine(canvas, false, { preserveDrawingBuffer: true }, false);
  engine.setSize(W, H);
  const scene = new Scene(engine);
  scene.clearColor = new Color4(0, 0, 0, 1);
  scene.ambientColor = new Color3(0, 0, 0);
  scene.imageProcessingConfiguration.applyByPostProcess = true;  // materials write linear values
  scene.imageProcessingConfiguration.toneMappingEnabled = false;
  scene.imageProcessingConfiguration.exposure = 1.0;
  await AppendSceneAsync("/scene/chart.gltf", scene);
  const camera = scene.cameras[0];
  scene.activeCamera = camera;
  const rtt = new RenderTargetTexture("chart", { width: W, height: H }, scene, false, true,
                                      Constants.TEXTURETYPE_FLOAT);
  rtt.renderList = scene.meshes.slice();
  rtt.activeCamera = camera;
  rtt.clearColor = new Color4(0, 0, 0, 1);
  await scene.whenReadyAsync();
  await new Promise((ok) => rtt.onAfterRenderObservable.addOnce(ok) && rtt.render());
  scene.render();
  rtt.render();
  const px = await rtt.readPixels();
  const buf = new Float32Array(px.buffer, px.byteOffset, W * H * 4);
  const bytes = new Uint8Array(buf.buffer, buf.byteOffset, buf.byteLength);
  let s = "";
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  window.__result = { data: btoa(s), width: W, height: H, version: Engine.Version };
} catch (e) {
  window.__result = { error: String((e && e.stack) || e) };
}
</script></body></html>
"""


def _node_modules() -> Path:
    from ..graders.babylon import package_folder

    core = package_folder()
    modules = core.parent.parent
    if not (modules / "@babylonjs" / "loaders" / "package.json").is_file():
        raise GraderUnavailable(f"npm package @babylonjs/loaders is not installed in {modules.parent}: {INSTALL}")
    return modules


def version() -> str:
    """Versions of @babylonjs/core and @babylonjs/loaders (GraderUnavailable when missing)."""
    modules = _node_modules()
    _browser.chromium()
    core = json.loads((modules / "@babylonjs" / "core" / "package.json").read_text())["version"]
    loaders = json.loads((modules / "@babylonjs" / "loaders" / "package.json").read_text())["version"]
    return f"core {core}, loaders {loaders}"


def render(scene_dir: Path, out: Path) -> list[str]:
    """Render ``scene_dir/chart.gltf`` with Babylon.js in Chromium into the EXR ``out``."""
    info = _browser.render_page(PAGE, Path(scene_dir), _node_modules(), Path(out), "Babylon.js")
    return [f"Babylon.js {info.get('version')} on SwiftShader, float RenderTargetTexture"]
