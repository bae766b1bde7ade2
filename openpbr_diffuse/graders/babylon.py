"""Babylon.js (npm ``@babylonjs/core``): its EON diffuse lobe as each light type computes it.

Babylon's shaders ship inside the npm package as JavaScript modules holding GLSL strings
(``Shaders/ShadersInclude/<name>.js``, each ``export const <name> = {name, shader}``) and WGSL
ones (``ShadersWGSL/ShadersInclude/``).  The grader reads the GLSL strings out of the
installed package at run time -- through ``node``, which imports the modules, so the strings
are exactly those the engine registers -- and runs them on llvmpipe like MaterialX's GLSL.
Nothing of Babylon's source is kept in this project.

``diffuseBRDF_EON(albedo, roughness, NdotL, NdotV, LdotV)`` (``pbrBRDFFunctions``) is not what a
Babylon scene renders: the PBR and OpenPBR materials call it from the light functions, which

- clamp the albedo to [0.1, 1] before the call, divide the result by the clamped albedo after
  it, and multiply by ``surfaceAlbedo`` in the final composition
  (``computeDiffuseLighting`` in ``pbrDirectLightingFunctions``; ``finalDiffuse*=surfaceAlbedo``
  in ``pbrBlockFinalUnlitComponents``, ``slab_diffuse*base_color`` in the OpenPBR material);
- set the lobe's inputs per light type (``pbrDirectLightingSetupFunctions``): the directional
  light sets ``LdotV = dot(L, V)``; the point and spot lights leave ``LdotV = 0``; the hemispheric
  light (``computeHemisphericDiffuseLighting``) and the rectangular area light
  (``computeAreaDiffuseLighting``, an LTC form factor) do not call the lobe at all;
- integrate it over the environment in the real-time-filtered IBL path (``irradiance`` in
  ``hdrFilteringFunctions``, cosine-weighted Hammersley samples).

Each path is a :class:`~.subject.Subject` of its own (:data:`PATHS`); the harness below replays,
for one light placed along ``wi``, the statements ``lightFragment`` / ``openpbrDirectLightingInit``
run for that light type (their presence in the installed package is checked, see
:data:`EXPECTED`), and divides out the light's attenuation.  What a harness returns:

- BRDF paths: ``finalDiffuse = computeXDiffuseLighting(...) * surfaceAlbedo`` = f·N·L·attenuation
  for a light of colour 1; divided by the attenuation (1/d², d = 2, physical falloff, the PBR
  material's default) and by Babylon's own ``NdotL``; the area light by the rectangle's exact
  cosine-weighted solid angle (computed here in float64);
- albedo paths: the response to a uniform white environment of radiance 1 (hemispheric light
  with sky = ground = 1; the filtered IBL with ``CUSTOM_IRRADIANCE_FILTERING_FUNCTION`` set to a
  white texel), which is the directional albedo E(μ_o).

The WGSL copies (``ShadersWGSL/ShadersInclude``) of the function and of the directional, point
and spot lights' functions run as a WGSL compute shader through ``wgpu`` (PyPI) on Mesa's Vulkan
driver (lavapipe), in a child process under the limits of user code (:mod:`._gpu_child`); their
``#define``/``#if`` lines, which Babylon's shader processor resolves, are resolved by the C
preprocessor.  The paths that need textures (area light: LTC samplers; filtered environment: a
cube map sampler) are graded in GLSL only.

Not graded: the spherical-harmonics and irradiance-map environment paths (``pbrBlockReflection``
without ``REALTIME_FILTERING``): they never call the lobe with the environment's directions, only
bend the normal towards V by (1 - N.V) r / 2 or scale a pre-filtered irradiance by the lobe at a
"dominant direction" computed on the CPU from the environment map.  Under a uniform environment
the first answers the environment's irradiance times rho, the same for every mu_o and roughness
(as the hemispheric light), and the second's dominant direction is the zero vector
(normalize(0): undefined).
"""

from __future__ import annotations

import json
import os
import re
import shutil
from collections.abc import Callable, Iterable
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from . import glsl, limits
from ._arrays import rows
from .errors import GraderUnavailable
from .subject import Subject

PACKAGE = "@babylonjs/core"
#: where ``.ci/run`` installs the package (``npm install --prefix``); overridden by the variable
CACHE_VARIABLE = "OPENPBR_DIFFUSE_NPM_CACHE"
INSTALL = (
    f"install it with: npm install --prefix ~/.cache/openpbr-diffuse/npm {PACKAGE} "
    f"(or set ${CACHE_VARIABLE} to the --prefix folder you used); Debian: apt-get install nodejs npm"
)
#: the include modules the harness concatenates, in dependency order
INCLUDES = (
    "helperFunctions",
    "importanceSampling",
    "pbrBRDFFunctions",
    "pbrDirectLightingFalloffFunctions",
    "pbrDirectLightingSetupFunctions",
    "pbrDirectLightingFunctions",
    "hdrFilteringFunctions",
)
#: statements of the installed shaders the harness replays; missing ones mean the harness is out
#: of date for that version, and the grader refuses to run rather than grade something else
EXPECTED = {
    "lightFragment": (
        "preInfo=computeDirectionalPreLightingInfo(light{X}.vLightData,viewDirectionW,normalW);",
        "preInfo=computePointAndSpotPreLightingInfo(light{X}.vLightData,viewDirectionW,normalW,vPositionW);",
        "preInfo=computeHemisphericPreLightingInfo(light{X}.vLightData,viewDirectionW,normalW);",
        "preInfo.NdotV=NdotV;",
        "preInfo.attenuation=computeDistanceLightFalloff_Physical(preInfo.lightDistanceSquared);",
        "preInfo.diffuseRoughness=diffuseRoughness;preInfo.surfaceAlbedo=surfaceAlbedo;",
        "info.diffuse=computeDiffuseLighting(preInfo,diffuse{X}.rgb);",
        "info.diffuse=computeHemisphericDiffuseLighting(preInfo,diffuse{X}.rgb,light{X}.vLightGround);",
        "info.diffuse=computeAreaDiffuseLighting(preInfo,diffuse{X}.rgb);",
    ),
    "pbrBlockGeometryInfo": ("float NdotV=absEps(NdotVUnclamped);",),
    "pbrBlockFinalUnlitComponents": ("finalDiffuse*=surfaceAlbedo;",),
    "pbrBlockFinalLitComponents": ("finalIrradiance*=surfaceAlbedo.rgb;",),
    "pbrBlockReflection": (
        "environmentIrradiance=irradiance(reflectionSampler,irradianceVector,"
        "vReflectionFilteringInfo,diffuseRoughness,surfaceAlbedo,irradianceView"
    ),
}
#: GLSL ES / WebGL names the engine's shader processor maps for desktop GLSL
PROLOGUE = "#define texture2D texture\n#define textureCubeLodEXT textureLod\n#define texture2DLodEXT textureLod\n"
#: point and spot lights at this distance along wi (attenuation 1/d^2 = 1/4, divided out)
LIGHT_DISTANCE = 2.0
#: the rectangular area light: half-size at distance 1 (solid angle ~1.6e-3 sr)
AREA_HALF = 0.02
#: the filtered IBL's sample count: Babylon's TEXTURE_FILTERING_QUALITY_OFFLINE (its HIGH is 64,
#: the OpenPBR material's default 8); the Hammersley estimate's error is then below the tolerance
IBL_SAMPLES = 4096
TOLERANCE, TOLERANCE_REASON = glsl.TOLERANCE, glsl.TOLERANCE_REASON
#: BRDF (f·N·L) and albedo paths: (key, label, kind)
PATHS = (
    ("function", "diffuseBRDF_EON alone", "brdf"),
    ("directional", "directional light", "brdf"),
    ("point", "point light", "brdf"),
    ("spot", "spot light", "brdf"),
    ("area", "rectangular area light", "brdf"),
    ("hemispheric", "hemispheric light", "albedo"),
    ("ibl_filtered", "filtered environment", "albedo"),
    ("wgsl_function", "WGSL diffuseBRDF_EON alone", "brdf"),
    ("wgsl_directional", "WGSL directional light", "brdf"),
    ("wgsl_point", "WGSL point light", "brdf"),
    ("wgsl_spot", "WGSL spot light", "brdf"),
)
#: the WGSL include modules (ShadersWGSL/ShadersInclude): the paths above that need no texture
WGSL_INCLUDES = (
    "helperFunctions",
    "pbrBRDFFunctions",
    "pbrDirectLightingFalloffFunctions",
    "pbrDirectLightingSetupFunctions",
    "pbrDirectLightingFunctions",
)

_EXTRACT = """
import { pathToFileURL } from "url";
import { readFileSync } from "fs";
const files = JSON.parse(readFileSync(0, "utf8"));
const out = {};
for (const f of files) {
  const m = await import(pathToFileURL(f).href);
  for (const v of Object.values(m)) if (v && typeof v.shader === "string") out[v.name] = v.shader;
}
process.stdout.write(JSON.stringify(out));
"""


def npm_prefix() -> Path:
    """The npm ``--prefix`` folder the package is installed in: ``$OPENPBR_DIFFUSE_NPM_CACHE`` or
    ``~/.cache/openpbr-diffuse/npm``.

    >>> npm_prefix().name
    'npm'
    """
    env = os.environ.get(CACHE_VARIABLE)
    return Path(env) if env else Path.home() / ".cache" / "openpbr-diffuse" / "npm"


def package_folder(prefix: Path | str | None = None) -> Path:
    """``node_modules/@babylonjs/core`` under ``prefix`` (default :func:`npm_prefix`), checked.

    ``prefix`` may also be the package folder itself.  Raises GraderUnavailable (with the
    install command) when the package is not there.

    >>> (package_folder() / "Shaders" / "ShadersInclude" / "pbrBRDFFunctions.js").is_file()
    True
    """
    root = Path(prefix) if prefix is not None else npm_prefix()
    folder = root / "node_modules" / "@babylonjs" / "core"
    if not (folder / "package.json").is_file():
        if (root / "package.json").is_file() and (root / "Shaders").is_dir():
            return root
        raise GraderUnavailable(f"{PACKAGE} is not installed in {root}: {INSTALL}")
    return folder


def package_version(folder: Path) -> str:
    """The ``version`` of the installed package's package.json.

    >>> package_version(package_folder()).split(".")[0].isdigit()
    True
    """
    return str(json.loads((folder / "package.json").read_text())["version"])


def installed_package(prefix: Path | str | None, package: str, holds: Callable[[Path], bool], install: str) -> Path:
    """``node_modules/<package>`` under ``prefix`` (default :func:`npm_prefix`), or ``prefix``
    itself when it is the package folder: the first with a package.json for which ``holds``
    is true.  Raises GraderUnavailable (with the install command ``install``) when neither is.

    >>> installed_package(None, "three", lambda f: (f / "build").is_dir(), "npm install three").name
    'three'
    """
    root = Path(prefix) if prefix is not None else npm_prefix()
    for folder in (root / "node_modules" / package, root):
        if (folder / "package.json").is_file() and holds(folder):
            return folder
    raise GraderUnavailable(f"npm package {package} is not installed in {root}: {install}")


def package_info(key: str, folder: Path, files: list[str]) -> dict[str, Any]:
    """The ``version`` of a Subject read from the npm package ``folder``: ``{key: its version,
    "source": folder, "files": files (relative to it), "sha256": the files' hash}``.

    >>> sorted(package_info("babylonjs", package_folder(), ["package.json"]))
    ['babylonjs', 'files', 'sha256', 'source']
    """
    return {
        key: package_version(folder),
        "source": str(folder),
        "files": files,
        "sha256": glsl.sources_hash([folder / f for f in files]),
    }


def require_node(what: str) -> None:
    """Raise GraderUnavailable when ``node`` (which reads ``what``) is not installed.

    >>> require_node("three's shader chunks")
    """
    if shutil.which("node") is None:
        raise GraderUnavailable(f"node is not installed (it reads {what}): apt-get install nodejs npm")


def run_node(script: str, job: Any, what: str, failure: str | None = None) -> Any:
    """The JSON that the ES module ``script`` writes to stdout for ``job`` (JSON on its stdin),
    run with node under the limits of user code.  Raises GraderUnavailable ("node could not
    import ``failure``", by default ``what``) when node fails.

    >>> run_node('import { readFileSync } from "fs"; '
    ...          'process.stdout.write(JSON.stringify(2 * JSON.parse(readFileSync(0, "utf8"))))', 21, "a number")
    42
    """
    run = limits.run_limited(
        ["node", "--input-type=module", "-e", script],
        input=json.dumps(job).encode(),
        label=f"reading {what} with node",
    )
    if run.returncode != 0:
        last = (run.stderr.decode(errors="replace").strip().splitlines() or ["?"])[-1]
        raise GraderUnavailable(f"node could not import {failure or what}: {last}")
    return json.loads(run.stdout)


@lru_cache(maxsize=8)
def _shaders(folder: Path, names: tuple, wgsl: bool) -> dict:
    require_node(f"{PACKAGE}'s shader modules")
    sub = "ShadersWGSL" if wgsl else "Shaders"
    files = []
    for name in names:
        for part in ("ShadersInclude", ""):
            f = folder / sub / part / f"{name}.js"
            if f.is_file():
                files.append(str(f))
                break
        else:
            raise GraderUnavailable(
                f"{folder / sub}: no shader module {name}.js in {PACKAGE} "
                f"{package_version(folder)} (the grader knows its 9.x layout)"
            )
    return run_node(_EXTRACT, files, f"{PACKAGE}'s shader modules")


def shaders(names: Iterable[str], folder: Path | None = None, *, wgsl: bool = False) -> dict[str, str]:
    """The GLSL (or WGSL) text of the named shader modules of the installed package.

    >>> text = shaders(["pbrBRDFFunctions"])["pbrBRDFFunctions"]
    >>> "vec3 diffuseBRDF_EON(vec3 albedo" in text
    True
    """
    folder = package_folder() if folder is None else folder
    return dict(_shaders(Path(folder).resolve(), tuple(names), bool(wgsl)))


_INCLUDE = re.compile(r"^[ \t]*#include<(\w+)>[^\n]*$", re.MULTILINE)


def _resolve(text: str, folder: Path, seen: set) -> str:
    """Babylon's ``#include<name>`` lines replaced by the modules' text (each once)."""

    def sub(m):
        name = m.group(1)
        if name in seen:
            return ""
        seen.add(name)
        return _resolve(shaders([name], folder)[name], folder, seen)

    return _INCLUDE.sub(sub, text)


def _check_expected(folder: Path) -> None:
    """Raise GraderUnavailable when a statement the harness replays is not in the package."""
    texts = shaders(tuple(EXPECTED), folder)
    missing = [f"{k}: {s}" for k, stmts in EXPECTED.items() for s in stmts if s not in texts[k]]
    if missing:
        raise GraderUnavailable(
            f"{PACKAGE} {package_version(folder)} no longer holds what the harness replays "
            f"({missing[0]}{' and more' if len(missing) > 1 else ''}): the grader needs updating"
        )


def _source(folder: Path, defines: dict) -> str:
    """The concatenated include modules, with the material's defines (EON diffuse model)."""
    seen = set(INCLUDES)
    texts = shaders(INCLUDES, folder)
    head = "".join(f"#define {k} {v}\n" for k, v in defines.items())
    return PROLOGUE + head + "\n".join(_resolve(texts[n], folder, seen) for n in INCLUDES)


# The harness bodies.  N = +z (the local frame); posW = 0; IN(0..2) = wi, IN(3..5) = wo,
# IN(6) = roughness, IN(7..9) = rho.  Each light path: the statements lightFragment runs for
# that light type in the PBR material (PBR branch, physical falloff), then
# finalDiffuse = diffuseBase * surfaceAlbedo.  OUT(0..2) = finalDiffuse, OUT(3) = Babylon's NdotL.
_SETUP = """
    vec3 wi = vec3(IN(0), IN(1), IN(2)); vec3 V = vec3(IN(3), IN(4), IN(5)); vec3 N = vec3(0.0, 0.0, 1.0);
    float roughness = IN(6); vec3 surfaceAlbedo = vec3(IN(7), IN(8), IN(9)); vec3 vPositionW = vec3(0.0);
    float NdotVUnclamped = dot(N, V); float NdotV = absEps(NdotVUnclamped);   // pbrBlockGeometryInfo
    preLightingInfo preInfo;
"""
_LIGHT = """
    preInfo.NdotV = NdotV;
    preInfo.roughness = 0.5; preInfo.diffuseRoughness = roughness; preInfo.surfaceAlbedo = surfaceAlbedo;
    vec3 d = {call} * surfaceAlbedo;                                         // finalDiffuse
    OUT(0) = d.x; OUT(1) = d.y; OUT(2) = d.z; OUT(3) = preInfo.NdotL;
"""
BODIES = {
    # the function alone, with the project's arguments
    "function": """
    vec3 wi = vec3(IN(0), IN(1), IN(2)); vec3 wo = vec3(IN(3), IN(4), IN(5));
    vec3 f = diffuseBRDF_EON(vec3(IN(7), IN(8), IN(9)), IN(6), wi.z, wo.z, dot(wi, wo));
    OUT(0) = f.x; OUT(1) = f.y; OUT(2) = f.z; OUT(3) = 1.0;""",
    # DirectionalLight: vLightData.xyz = the light's direction of travel, -wi
    "directional": _SETUP
    + """
    preInfo = computeDirectionalPreLightingInfo(vec4(-wi, 0.0), V, N);
    preInfo.attenuation = 1.0;"""
    + _LIGHT.replace("{call}", "computeDiffuseLighting(preInfo, vec3(1.0))"),
    # PointLight at LIGHT_DISTANCE along wi, physical falloff
    "point": _SETUP
    + """
    preInfo = computePointAndSpotPreLightingInfo(vec4(wi * LIGHT_DISTANCE, 0.0), V, N, vPositionW);
    preInfo.attenuation = computeDistanceLightFalloff_Physical(preInfo.lightDistanceSquared);"""
    + _LIGHT.replace("{call}", "computeDiffuseLighting(preInfo, vec3(1.0))"),
    # SpotLight at LIGHT_DISTANCE along wi aimed at the shaded point (cone axis: falloff 1), 90 deg cone
    "spot": _SETUP
    + """
    preInfo = computePointAndSpotPreLightingInfo(vec4(wi * LIGHT_DISTANCE, 0.0), V, N, vPositionW);
    preInfo.attenuation = computeDistanceLightFalloff_Physical(preInfo.lightDistanceSquared);
    preInfo.attenuation *= computeDirectionalLightFalloff_Physical(-wi, preInfo.L, cos(0.7853981634));"""
    + _LIGHT.replace("{call}", "computeDiffuseLighting(preInfo, vec3(1.0))"),
    # RectAreaLight centred at distance 1 along wi, facing the point; halfWidth x halfHeight = wi
    "area": _SETUP
    + """
    vec3 t1 = normalize(abs(wi.z) < 0.999 ? cross(vec3(0.0, 0.0, 1.0), wi) : vec3(1.0, 0.0, 0.0));
    vec3 t2 = cross(wi, t1);
    preInfo = computeAreaPreLightingInfo(areaLightsLTC1Sampler, areaLightsLTC2Sampler, V, N, vPositionW,
                                         vec4(wi, 0.0), AREA_HALF * t1, AREA_HALF * t2, 0.5);
    preInfo.attenuation = 1.0; preInfo.NdotL = 1.0;"""
    + _LIGHT.replace("{call}", "computeAreaDiffuseLighting(preInfo, vec3(1.0))"),
}
ALBEDO_BODIES = {
    # HemisphericLight: sky direction = the normal, sky = ground = 1 (a uniform white environment)
    "hemispheric": """
    float mu = IN(0); vec3 V = vec3(sqrt(max(0.0, 1.0 - mu*mu)), 0.0, mu); vec3 N = vec3(0.0, 0.0, 1.0);
    vec3 surfaceAlbedo = vec3(IN(2), IN(3), IN(4));
    preLightingInfo preInfo = computeHemisphericPreLightingInfo(vec4(N, 0.0), V, N);
    preInfo.NdotV = absEps(dot(N, V)); preInfo.attenuation = 1.0;
    preInfo.diffuseRoughness = IN(1); preInfo.surfaceAlbedo = surfaceAlbedo;
    vec3 d = computeHemisphericDiffuseLighting(preInfo, vec3(1.0), vec3(1.0)) * surfaceAlbedo;
    OUT(0) = d.x; OUT(1) = d.y; OUT(2) = d.z;""",
    # reflectionBlock with REALTIME_FILTERING: irradiance(reflectionSampler, irradianceVector = N,
    # vReflectionFilteringInfo, diffuseRoughness, surfaceAlbedo, irradianceView = V) under a
    # white environment; finalIrradiance = environmentIrradiance * surfaceAlbedo
    "ibl_filtered": """
    float mu = IN(0); vec3 V = vec3(sqrt(max(0.0, 1.0 - mu*mu)), 0.0, mu); vec3 N = vec3(0.0, 0.0, 1.0);
    vec3 surfaceAlbedo = vec3(IN(2), IN(3), IN(4));
    vec3 e = irradiance(0.0, N, vec2(256.0, 8.0), IN(1), surfaceAlbedo, V) * surfaceAlbedo;
    OUT(0) = e.x; OUT(1) = e.y; OUT(2) = e.z;""",
}
_DEFINES = {
    "BASE_DIFFUSE_MODEL": "BRDF_DIFFUSE_MODEL_EON",
    "WEBGL2": "1",
    "USEPHYSICALLIGHTFALLOFF": "1",
    "LIGHT_DISTANCE": repr(LIGHT_DISTANCE),
    "AREA_HALF": repr(AREA_HALF),
}
_PATH_DEFINES = {
    "area": {"AREALIGHTUSED": "1", "AREALIGHTSUPPORTED": "1"},
    # Babylon's own hooks: the texture argument becomes a float, and each sample reads white
    "ibl_filtered": {
        "NUM_SAMPLES": f"{IBL_SAMPLES}u",
        "CUSTOM_IRRADIANCE_FILTERING_INPUT": "float grader_white,",
        "CUSTOM_IRRADIANCE_FILTERING_FUNCTION": "vec3 c = vec3(1.0);",
    },
}


# WGSL: Babylon's WGSL keeps #define/#if lines for its own shader processor; the C
# preprocessor (cpp -P) resolves them the same way for these files.  The harness is the same
# sequence of calls as the GLSL bodies above.
_WGSL_MAIN = """
@group(0) @binding(0) var<storage, read> grader_in: array<f32>;
@group(0) @binding(1) var<storage, read_write> grader_out: array<f32>;
fn IN(row: u32, k: u32) -> f32 { return grader_in[row * 10u + k]; }
@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) gid: vec3u) {
    let row = gid.x;
    let wi = vec3f(IN(row, 0u), IN(row, 1u), IN(row, 2u)); let V = vec3f(IN(row, 3u), IN(row, 4u), IN(row, 5u));
    let N = vec3f(0.0, 0.0, 1.0); let roughness = IN(row, 6u); let surfaceAlbedo = vec3f(IN(row, 7u), IN(row, 8u), IN(row, 9u));
    var d = vec3f(0.0); var NdotL = 1.0;
BODY
    grader_out[row * 4u] = d.x; grader_out[row * 4u + 1u] = d.y; grader_out[row * 4u + 2u] = d.z;
    grader_out[row * 4u + 3u] = NdotL;
}
"""
_WGSL_LIGHT = """
    preInfo.NdotV = absEps(dot(N, V));
    preInfo.roughness = 0.5; preInfo.diffuseRoughness = roughness; preInfo.surfaceAlbedo = surfaceAlbedo;
    d = computeDiffuseLighting(preInfo, vec3f(1.0)) * surfaceAlbedo; NdotL = preInfo.NdotL;"""
WGSL_BODIES = {
    "wgsl_function": "    d = diffuseBRDF_EON(surfaceAlbedo, roughness, wi.z, V.z, dot(wi, V));",
    "wgsl_directional": """
    var preInfo = computeDirectionalPreLightingInfo(vec4f(-wi, 0.0), V, N);
    preInfo.attenuation = 1.0;"""
    + _WGSL_LIGHT,
    "wgsl_point": f"""
    var preInfo = computePointAndSpotPreLightingInfo(vec4f(wi * {LIGHT_DISTANCE!r}, 0.0), V, N, vec3f(0.0));
    preInfo.attenuation = computeDistanceLightFalloff_Physical(preInfo.lightDistanceSquared);"""
    + _WGSL_LIGHT,
    "wgsl_spot": f"""
    var preInfo = computePointAndSpotPreLightingInfo(vec4f(wi * {LIGHT_DISTANCE!r}, 0.0), V, N, vec3f(0.0));
    preInfo.attenuation = computeDistanceLightFalloff_Physical(preInfo.lightDistanceSquared);
    preInfo.attenuation *= computeDirectionalLightFalloff_Physical(-wi, preInfo.L, cos(0.7853981634));"""
    + _WGSL_LIGHT,
}


def _wgsl_source(folder: Path, key: str) -> str:
    """The WGSL include modules, preprocessed (EON diffuse model, physical falloff), and the harness."""
    return _wgsl_includes(folder) + _WGSL_MAIN.replace("BODY", WGSL_BODIES[key])


@lru_cache(maxsize=8)
def _wgsl_includes(folder: Path) -> str:
    """The WGSL include modules after the C preprocessor: the same text for every WGSL path."""
    if shutil.which("cpp") is None:
        raise GraderUnavailable(
            "cpp (the C preprocessor, for Babylon's #if lines in WGSL) is missing: apt-get install g++"
        )
    texts = shaders(WGSL_INCLUDES, folder, wgsl=True)
    head = "".join(
        f"#define {k} {v}\n"
        for k, v in (("BASE_DIFFUSE_MODEL", "BRDF_DIFFUSE_MODEL_EON"), ("USEPHYSICALLIGHTFALLOFF", "1"))
    )
    text = head + "\n".join(texts[n] for n in WGSL_INCLUDES)
    run = limits.run_limited(
        ["cpp", "-P", "-undef", "-nostdinc", "-w", "-"], input=text.encode(), label="preprocessing Babylon's WGSL"
    )
    if run.returncode != 0:
        raise GraderUnavailable(f"cpp could not preprocess Babylon's WGSL: {run.stderr.decode(errors='replace')[:200]}")
    return run.stdout.decode()


def _run_wgsl(source_text: str, inputs: np.ndarray, n_out: int, label: str) -> np.ndarray:
    """Run a WGSL compute shader (10 floats in, ``n_out`` out per row) in a child under the limits."""
    import pickle

    from ._gpu_child import CHILD

    inputs = np.ascontiguousarray(inputs, np.float32)
    job = {
        "source": source_text,
        "n_in": inputs.shape[1],
        "n_out": n_out,
        "rows": inputs.shape[0],
        "inputs": inputs.tobytes(),
    }
    run = limits.worker(limits.script_command(CHILD, "wgsl")).request(
        pickle.dumps(job), label=f"{label} (WGSL through wgpu)"
    )
    err = [line for line in run.stderr.decode(errors="replace").splitlines() if "XDG_RUNTIME_DIR" not in line]
    if run.returncode != 0:
        raise GraderUnavailable(f"{label} (WGSL): {err[-1] if err else f'status {run.returncode}'}")
    out = np.frombuffer(run.stdout, np.float32)
    if out.size != inputs.shape[0] * n_out:
        raise GraderUnavailable(
            f"{label} (WGSL): the child wrote {out.size} values, expected {inputs.shape[0] * n_out}"
        )
    return out.reshape(-1, n_out).copy()


def rect_cosine_solid_angle(wi: np.ndarray, half: float = AREA_HALF) -> np.ndarray:
    """∫ cos θ dω over the area light's rectangle (centre wi at distance 1, half-size ``half``),
    exact for a polygon above the horizon (Lambert's formula), float64: (n,).

    A square of side 0.02 seen head-on: 4e-4 (1 - 4 a^2 / 3) to second order in a = 0.01:

    >>> w = np.array([[0.0, 0.0, 1.0]])
    >>> float(rect_cosine_solid_angle(w, 0.01)[0] / 4e-4 - 1).__round__(7)
    -0.0001333
    """
    wi = np.asarray(wi, float)
    z = np.array([0.0, 0.0, 1.0])
    t1 = np.where(
        (np.abs(wi[:, 2]) < 0.999)[:, None],
        np.cross(np.broadcast_to(z, wi.shape), wi),
        np.broadcast_to([1.0, 0.0, 0.0], wi.shape),
    )
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(wi, t1)
    corners = [wi + half * (a * t1 + b * t2) for a, b in ((1, -1), (-1, -1), (-1, 1), (1, 1))]
    total = np.zeros(wi.shape[0])
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        a = a / np.linalg.norm(a, axis=1, keepdims=True)
        b = b / np.linalg.norm(b, axis=1, keepdims=True)
        c = np.cross(a, b)
        gamma = np.arccos(np.clip(np.einsum("ij,ij->i", a, b), -1, 1))
        total += gamma * c[:, 2] / np.linalg.norm(c, axis=1)
    return np.abs(total) / 2.0


def path_subject(key: str, folder: Path | None = None) -> Subject:
    """The :class:`~.subject.Subject` of one path of :data:`PATHS` (``"point"``, ``"ibl_filtered"``, ...).

    >>> s = path_subject("directional")
    >>> f = s.brdf(np.array([[0.0, 0.0, 1.0]]), np.array([[0.6, 0.0, 0.8]]), np.array([0.0]),
    ...            np.array([[0.5, 0.5, 0.5]]))
    >>> bool(np.allclose(f, 0.5 / np.pi, rtol=1e-6))    # roughness 0: Lambert
    True
    """
    labels = {k: (label, kind) for k, label, kind in PATHS}
    if key not in labels:
        raise ValueError(f"path: {key!r} is not one of {', '.join(labels)}")
    folder = package_folder() if folder is None else Path(folder)
    _check_expected(folder)
    label, kind = labels[key]
    version = package_version(folder)
    code = "" if key.startswith("wgsl_") else _source(folder, {**_DEFINES, **_PATH_DEFINES.get(key, {})})
    info = package_info("babylonjs", folder, [f"Shaders/ShadersInclude/{n}.js" for n in INCLUDES])
    common: dict[str, Any] = {"tolerance": TOLERANCE, "tolerance_reason": TOLERANCE_REASON, "version": info}
    name = f"babylonjs {label}"
    run_label = f"Babylon.js {version} ({label})"
    if key.startswith("wgsl_"):
        wgsl_text = _wgsl_source(folder, key)
        wfiles = [f"ShadersWGSL/ShadersInclude/{n}.js" for n in WGSL_INCLUDES]
        info.update(files=wfiles, sha256=glsl.sources_hash([folder / f for f in wfiles]))
    if kind == "brdf":
        if key.startswith("wgsl_"):

            def run(x):
                return _run_wgsl(wgsl_text, x, 4, run_label)
        else:
            kernel = glsl.Kernel(code=code, n_in=10, n_out=4, body=BODIES[key])

            def run(x):
                return kernel.run(x, run_label)

        def brdf(wi, wo, roughness, rho):
            out = run(rows(wi, wo, roughness, rho)).astype(np.float64)
            resp = out[:, :3]
            if key in ("point", "spot", "wgsl_point", "wgsl_spot"):
                resp = resp * LIGHT_DISTANCE**2  # the attenuation 1/d^2 divided out
            if key == "area":
                f = resp / rect_cosine_solid_angle(np.asarray(wi, float))[:, None]
            else:
                f = resp / out[:, 3:4]  # Babylon's NdotL divided out
            below = np.asarray(wi)[:, 2] <= 0
            f[below] = resp[below]
            return f

        def domain(wi, wo):
            # a renderer shades the side the viewer sees (NdotV = |N.V|); the area light only
            # where its rectangle is wholly above the horizon (its LTC clips at the horizon)
            ok = np.asarray(wo)[:, 2] > 0
            if key.endswith("function"):  # the light functions call it with NdotL >= Epsilon only
                ok &= np.asarray(wi)[:, 2] > 0
            if key == "area":
                ok &= np.asarray(wi)[:, 2] > 2 * AREA_HALF
            return ok

        return Subject(
            name=name, model="eon", brdf=brdf, brdf_domain=domain, **common, notes=[f"{label}: " + _NOTES[key]]
        )
    kernel = glsl.Kernel(code=code, n_in=5, n_out=3, body=ALBEDO_BODIES[key])

    def albedo(mu, roughness, rho):
        return kernel.run(rows(mu, roughness, rho), run_label).astype(np.float64)

    return Subject(name=name, model="eon", albedo=albedo, **common, notes=[f"{label}: " + _NOTES[key]])


_CLAMP = (
    "the lobe is called with c = clamp(rho, 0.1, 1) and its result scaled by rho/c: "
    "f = (rho/c) f_EON~(c), f_EON~ with the Eq. 14 fit of E_F"
)
_NOTES = {
    "function": "diffuseBRDF_EON(rho, r, wi.z, wo.z, wi.wo) called directly (pbrBRDFFunctions): "
    "EON with the Eq. 14 fit of E_F (E_FON_approx)",
    "directional": "computeDirectionalPreLightingInfo + computeDiffuseLighting, x surfaceAlbedo, divided by "
    "Babylon's NdotL; " + _CLAMP,
    "point": f"computePointAndSpotPreLightingInfo (light at d = {LIGHT_DISTANCE:g} along wi) + physical falloff "
    "+ computeDiffuseLighting, x surfaceAlbedo, divided by 1/d^2 and NdotL; the setup leaves "
    "LdotV = 0, so the lobe sees s = -mu_i mu_o whatever the azimuths; " + _CLAMP,
    "spot": "as the point light, aimed at the point (computeDirectionalLightFalloff_Physical = 1 on the axis); "
    "LdotV = 0 as for the point light",
    "area": f"computeAreaPreLightingInfo (rectangle of half-size {AREA_HALF:g} at distance 1 along wi) + "
    "computeAreaDiffuseLighting, x surfaceAlbedo, divided by the rectangle's cosine-weighted solid "
    f"angle (rows with mu_i <= {2 * AREA_HALF:g} not graded); the diffuse part is an LTC form factor "
    "with the identity matrix, i.e. Lambert (rho/pi, no roughness), and 0 at mu_o = 1 exactly "
    "(its frame T1 = normalize(V - N (V.N)) is undefined there)",
    "hemispheric": "computeHemisphericPreLightingInfo + computeHemisphericDiffuseLighting with sky = ground = 1 "
    "(a uniform white environment), x surfaceAlbedo: rho for every mu_o and roughness "
    "(the lobe is not called)",
    "ibl_filtered": f"irradiance() of hdrFilteringFunctions (REALTIME_FILTERING) with NUM_SAMPLES = {IBL_SAMPLES} "
    "(TEXTURE_FILTERING_QUALITY_OFFLINE) under a white environment, x surfaceAlbedo: the clamped "
    "lobe above integrated with cosine-weighted Hammersley samples (the estimate is poor at "
    "grazing mu_o, where f has a 1/mu_i peak the cosine pdf does not follow)",
    "wgsl_function": "the WGSL copy of diffuseBRDF_EON (ShadersWGSL), run through wgpu",
    "wgsl_directional": "the WGSL copies of the directional light's functions, run through wgpu",
    "wgsl_point": "the WGSL copies of the point light's functions, run through wgpu (LdotV = 0 there too)",
    "wgsl_spot": "the WGSL copies of the spot light's functions, run through wgpu (LdotV = 0 there too)",
}


def subject(source: Path | None = None) -> Subject:
    """Babylon.js: one Subject whose ``paths`` are every light type's and the environment's.

    ``source`` is an npm prefix or a ``@babylonjs/core`` folder (default: the project's npm cache).
    The top-level ``brdf`` is the directional light's path and ``albedo`` the filtered
    environment's (the report's pictures); the grades are per path.

    >>> [label for label, _ in subject().paths][:3]
    ['diffuseBRDF_EON alone', 'directional light', 'point light']
    """
    folder = package_folder(source)
    paths = [(label, path_subject(key, folder)) for key, label, _ in PATHS]
    by = dict(paths)
    version = package_version(folder)
    top = by["directional light"]
    return Subject(
        name="babylonjs",
        model="eon",
        tolerance=TOLERANCE,
        tolerance_reason=TOLERANCE_REASON,
        version={**top.version, "gl": glsl.gl_version()},
        brdf=top.brdf,
        brdf_domain=top.brdf_domain,
        albedo=by["filtered environment"].albedo,
        notes=[f"{PACKAGE} {version}: graded per light type and environment path"]
        + [n for _, s in paths for n in s.notes],
        paths=paths,
    )
