"""three.js renders the chart's glTF: ``GLTFLoader`` (KHR_materials_diffuse_roughness,
KHR_materials_specular, KHR_lights_punctual) and ``WebGLRenderer`` in headless Chromium.

The page loads ``chart.gltf`` as a three.js user would, renders with the glTF's orthographic
camera into a ``FloatType`` ``WebGLRenderTarget`` (``NoToneMapping``, ``LinearSRGBColorSpace``,
no antialiasing, pixel ratio 1), reads the pixels back with ``readRenderTargetPixels`` and the
child writes them as a float EXR.  three.js's lights are physical (r155 and later): a
directional light of intensity E lux gives irradiance E.  three is served from the npm cache
with an import map (offline).

Example
-------
>>> "GLTFLoader" in PAGE and "FloatType" in PAGE
True
"""

from __future__ import annotations

from pathlib import Path

from . import _browser

PAGE = """<!doctype html>
<html><head><meta charset="utf-8"><title>openpbr-diffuse chart: three.js</title>
<script type="importmap">
{"imports": {"three": "/npm/three/build/three.module.js", "three/addons/": "/npm/three/examples/jsm/"}}
</script></head><body>
<script type="module">
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
try {
  const chart = await (await fetch("/scene/chart.json")).json();
  const W = chart.width, H = chart.height;
  const renderer = new THREE.WebGLRenderer({ antialias: false });
  renderer.setPixelRatio(1);
  renderer.setSize(W, H, false);
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  renderer.setClearColor(0x000000, 1);
  const gltf = await new GLTFLoader().loadAsync("/scene/chart.gltf");
  const camera = gltf.cameras[0];
  const target = new THREE.WebGLRenderTarget(W, H, { type: THREE.FloatType, colorSpace: THREE.LinearSRGBColorSpace });
  renderer.setRenderTarget(target);
  renderer.render(gltf.scene, camera);
  const buf = new Float32Array(W * H * 4);
  renderer.readRenderTargetPixels(target, 0, 0, W, H, buf);
  const bytes = new Uint8Array(buf.buffer);
  let s = "";
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  window.__result = { data: btoa(s), width: W, height: H, version: "r" + THREE.REVISION };
} catch (e) {
  window.__result = { error: String((e && e.stack) || e) };
}
</script></body></html>
"""


def _node_modules() -> Path:
    from ..graders.threejs import package_folder

    return package_folder().parent


def version() -> str:
    """The installed three's package version (GraderUnavailable when three or Chromium is missing)."""
    from ..graders.threejs import package_folder, package_version

    _browser.chromium()
    return package_version(package_folder())


def render(scene_dir: Path, out: Path) -> list[str]:
    """Render ``scene_dir/chart.gltf`` with three.js in Chromium into the EXR ``out``."""
    info = _browser.render_page(PAGE, Path(scene_dir), _node_modules(), Path(out), "three.js")
    return [f"three.js {info.get('version')} WebGLRenderer on SwiftShader, FloatType render target"]
