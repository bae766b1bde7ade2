"""three-gpu-pathtracer (npm): its WGSL ``eonBrdf``, ``fonBrdf`` and EON sampler, run through wgpu.

The package's WebGPU path tracer defines its diffuse lobe in
``src/webgpu/nodes/eon.wgsl.js`` as three.js TSL ``wgslFn`` nodes (WGSL text plus the nodes it
includes: the ``constants`` code node and the ``SurfaceRecord`` struct node of
``structs.wgsl.js``).  The grader imports that module with ``node`` -- three.js's own node
classes hold the text, so it is exactly what the renderer compiles -- walks each function's
includes in dependency order, writes the struct from the node's member list, and runs the
result as a WGSL compute shader through ``wgpu`` on Mesa's Vulkan driver (lavapipe), in a child
process under the limits of user code (:mod:`._gpu_child`).  Nothing of the package's source is
kept in this project.

How the material calls them (``src/webgpu/materials/GltfCompliantMaterial.js``, whose statements
the harness replays, checked present, :data:`EXPECTED`):

- BRDF: ``if (NdotL > 0.0) { let diffuseVdotH = sqrt(saturate(0.5 * (1.0 + dot(ctx.V, ctx.L))));
  reflection = diffuseBrdf(NdotV, NdotL, diffuseVdotH, surf) }`` with ``NdotV = ctx.V.z``,
  ``NdotL = ctx.L.z`` in the local frame: f above the horizon, 0 below.  ``diffuseBrdf`` is
  ``eonBrdf`` by default (a constructor option may set ``fonBrdf``);
- sampler: ``wi = eonDirection(wo, surf.diffuseRoughness, directionUV)`` and its density
  ``eonPdf(wo, wi, surf.diffuseRoughness)`` (the lobe's share of the mixture pdf).

Paths (:data:`PATHS`): ``eonBrdf`` as ``eon`` (what its comment cites, Listing 2 of Portsmouth
et al. 2025) and as ``eon_approx`` (its E_FON is the Eq. 14 fit ``eonDirectionalAlbedo``), with
the sampler on the ``eon`` path; ``fonBrdf`` as ``fon``.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from . import glsl
from ._arrays import rows
from .babylon import (
    CACHE_VARIABLE,
    _run_wgsl,
    installed_package,
    package_info,
    package_version,
    require_node,
    run_node,
)
from .errors import GraderUnavailable
from .subject import Subject

PACKAGE = "three-gpu-pathtracer"
INSTALL = (
    f"install it with: npm install --prefix ~/.cache/openpbr-diffuse/npm --ignore-scripts three {PACKAGE} "
    f"(or set ${CACHE_VARIABLE} to the --prefix folder you used); Debian: apt-get install nodejs npm"
)
#: the module holding the lobe, its exports the harness calls, and the material that calls them
MODULE = "src/webgpu/nodes/eon.wgsl.js"
EXPORTS = ("eonBrdfFunc", "fonBrdfFunc", "eonDirectionFunc", "eonPDFFunc")
MATERIAL = "src/webgpu/materials/GltfCompliantMaterial.js"
#: statements of the material the harness replays (compared without white space)
EXPECTED = (
    "let NdotV = ctx.V.z;",
    "let NdotL = ctx.L.z;",
    "if ( NdotL > 0.0 ) {",
    "let diffuseVdotH = sqrt( saturate( 0.5 * ( 1.0 + dot( ctx.V, ctx.L ) ) ) );",
    "let reflection = ${ this.diffuseBrdf }( NdotV, NdotL, diffuseVdotH, surf );",
    "diffuseBrdf = eonBrdfFunc,",
    "wi = ${ eonDirectionFunc }( wo, surf.diffuseRoughness, directionUV );",
    "${ eonPDFFunc }( wo, wi, surf.diffuseRoughness );",
)
#: TSL type names a struct node may use, as WGSL spells them
_TYPES = {"float": "f32", "int": "i32", "uint": "u32", "vec2": "vec2f", "vec3": "vec3f", "vec4": "vec4f"}
#: WGSL: every row in 11 floats (mode, wo, wi or u, roughness, rho), out 7 floats
N_IN, N_OUT = 11, 7
_MAIN = """
@group(0) @binding(0) var<storage, read> grader_in: array<f32>;
@group(0) @binding(1) var<storage, read_write> grader_out: array<f32>;
fn IN(row: u32, k: u32) -> f32 { return grader_in[row * 11u + k]; }
fn OUT(row: u32, k: u32, v: f32) { grader_out[row * 7u + k] = v; }
@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) gid: vec3u) {
    let row = gid.x;
    let mode = IN(row, 0u);
    let wo = vec3f(IN(row, 1u), IN(row, 2u), IN(row, 3u));
    let a = vec3f(IN(row, 4u), IN(row, 5u), IN(row, 6u));
    let roughness = IN(row, 7u);
    var r = array<f32, 7>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    if (mode < 0.5) {
        // bsdfEval's diffuse block: wi = a, local frame (ctx.V = wo, ctx.L = wi)
        var surf: SurfaceRecord;
        surf.diffuseRoughness = roughness;
        surf.color = vec3f(IN(row, 8u), IN(row, 9u), IN(row, 10u));
        let NdotV = wo.z;
        let NdotL = a.z;
        if ( NdotL > 0.0 ) {
            let diffuseVdotH = sqrt( saturate( 0.5 * ( 1.0 + dot( wo, a ) ) ) );
            let e = eonBrdf( NdotV, NdotL, diffuseVdotH, surf );
            let f = fonBrdf( NdotV, NdotL, diffuseVdotH, surf );
            r[0] = e.x; r[1] = e.y; r[2] = e.z; r[3] = f.x; r[4] = f.y; r[5] = f.z;
        }
    } else if (mode < 1.5) {
        // bsdfSample's diffuse branch: u = a.xy, then the lobe's pdf at the sampled wi
        let wi = eonDirection( wo, roughness, a.xy );
        r[0] = wi.x; r[1] = wi.y; r[2] = wi.z; r[3] = eonPdf( wo, wi, roughness );
    } else {
        r[3] = eonPdf( wo, a, roughness );
    }
    for (var k = 0u; k < 7u; k = k + 1u) { OUT(row, k, r[k]); }
}
"""
TOLERANCE = glsl.TOLERANCE
TOLERANCE_REASON = (
    "WGSL on lavapipe: float32 arithmetic (1e-4 relative, as check FILE); 5e-5 absolute as the GLSL graders"
)
#: (label, model, function) of the BRDF paths; the sampler is on the first
PATHS = (("eonBrdf as eon", "eon", "eon"), ("eonBrdf as eon_approx", "eon_approx", "eon"), ("fonBrdf", "fon", "fon"))

_EXTRACT = """
import { pathToFileURL } from "url";
import { readFileSync } from "fs";
const { file, names } = JSON.parse(readFileSync(0, "utf8"));
const m = await import(pathToFileURL(file).href);
const seen = new Set(); const out = [];
function walk(n) {
  if (!n || seen.has(n)) return; seen.add(n);
  for (const i of (n.includes || [])) walk(i);
  if (n.isStructTypeNode) out.push({ struct: n.name, members: n.membersLayout.map(x => [x.name, x.type]) });
  else if (typeof n.code === "string") out.push({ code: n.code });
  else throw new Error("an include that is neither code nor a struct: " + n.type);
}
for (const name of names) { if (!m[name]) throw new Error(file + " exports no " + name); walk(m[name]); }
process.stdout.write(JSON.stringify(out));
"""


def package_folder(prefix: Path | str | None = None) -> Path:
    """``node_modules/three-gpu-pathtracer`` under ``prefix`` (default: the project's npm cache), checked.

    ``prefix`` may also be the package folder itself (with ``three`` where node finds it).

    >>> (package_folder() / MODULE).is_file()
    True
    """
    return installed_package(prefix, PACKAGE, lambda folder: (folder / MODULE).is_file(), INSTALL)


def _squash(text: str) -> str:
    return re.sub(r"\s+", "", text)


def _struct(name: str, members: list) -> str:
    fields = []
    for field, kind in members:
        kind = _TYPES.get(kind.strip(), kind.strip())
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", kind):
            raise GraderUnavailable(f"{PACKAGE}: struct {name} member {field} has a type WGSL does not know: {kind!r}")
        fields.append(f"    {field}: {kind},")
    return f"struct {name} {{\n" + "\n".join(fields) + "\n};\n"


@lru_cache(maxsize=4)
def wgsl_functions(folder: Path) -> str:
    """The WGSL of :data:`EXPORTS` and everything they include, in dependency order (read through node).

    >>> text = wgsl_functions(package_folder())
    >>> text.index("struct SurfaceRecord") < text.index("fn eonBrdf(")
    True
    """
    require_node(f"{PACKAGE}'s WGSL nodes")
    material = _squash((Path(folder) / MATERIAL).read_text()) if (Path(folder) / MATERIAL).is_file() else ""
    missing = [s for s in EXPECTED if _squash(s) not in material]
    if missing:
        raise GraderUnavailable(
            f"{PACKAGE} {package_version(folder)}: {MATERIAL} no longer holds {missing[0]!r}: "
            "the harness replays 0.0.26's calls and would grade something else"
        )
    parts = run_node(
        _EXTRACT,
        {"file": str(Path(folder) / MODULE), "names": list(EXPORTS)},
        f"{PACKAGE}'s WGSL nodes",
        f"{PACKAGE}'s {MODULE} (it needs npm three too)",
    )
    return "\n".join(p["code"] if "code" in p else _struct(p["struct"], p["members"]) for p in parts)


def _runner(folder: Path) -> Callable[[np.ndarray], np.ndarray]:
    text = wgsl_functions(folder) + _MAIN
    label = f"{PACKAGE} {package_version(folder)}"

    def run(x: np.ndarray) -> np.ndarray:
        return _run_wgsl(text, x, N_OUT, label).astype(np.float64)

    return run


def subject(source_folder: Path | None = None) -> Subject:
    """three-gpu-pathtracer: a Subject whose ``paths`` are ``eonBrdf`` (as eon, as eon_approx) and ``fonBrdf``.

    ``source_folder`` is an npm prefix or a ``three-gpu-pathtracer`` folder (default: the
    project's npm cache).  The sampler (``eonDirection`` / ``eonPdf``) is on the first path.

    >>> s = subject()
    >>> [label for label, _ in s.paths]
    ['eonBrdf as eon', 'eonBrdf as eon_approx', 'fonBrdf']
    >>> f = s.brdf(np.array([[0.0, 0.0, 1.0]]), np.array([[0.6, 0.0, 0.8]]), np.array([0.0]),
    ...            np.array([[0.5, 0.5, 0.5]]))
    >>> bool(np.allclose(f, 0.5 / np.pi, rtol=1e-6))    # roughness 0: Lambert
    True
    """
    folder = package_folder(source_folder)
    version = package_version(folder)
    run = _runner(folder)
    info = package_info(PACKAGE, folder, [MODULE, "src/webgpu/nodes/structs.wgsl.js", MATERIAL])

    def brdf_of(which: str) -> Callable[..., np.ndarray]:
        cols = slice(0, 3) if which == "eon" else slice(3, 6)

        def brdf(wi, wo, roughness, rho):
            return run(rows(0.0, wo, wi, roughness, rho, n=len(roughness)))[:, cols]

        return brdf

    def sample(wo, roughness, u):
        u = np.asarray(u, float)
        out = run(rows(1.0, wo, u, 0.0, roughness, 0.0, 0.0, 0.0, n=u.shape[0]))
        return out[:, :3], out[:, 3]

    def pdf(wo, wi, roughness):
        return run(rows(2.0, wo, wi, roughness, 0.0, 0.0, 0.0, n=np.asarray(wi).shape[0]))[:, 3]

    def domain(wi, wo):
        # a renderer traces from the viewer's side (the local frame's wo.z > 0)
        return np.asarray(wo)[:, 2] > 0

    common: dict[str, Any] = {"tolerance": TOLERANCE, "tolerance_reason": TOLERANCE_REASON, "version": info}
    paths = []
    for k, (label, model, which) in enumerate(PATHS):
        extra: dict[str, Any] = {"sample": sample, "pdf": pdf} if k == 0 else {}
        paths.append(
            (
                label,
                Subject(
                    name=f"{PACKAGE} {label}", model=model, brdf=brdf_of(which), brdf_domain=domain, **common, **extra
                ),
            )
        )
    notes = [
        f"npm {PACKAGE} {version}: {MODULE} (three.js TSL wgslFn nodes), called as {MATERIAL} does",
        "BRDF: f(NdotV = wo.z, NdotL = wi.z, VdotH = sqrt(saturate((1 + wo.wi) / 2))) for wi.z > 0, 0 below",
        "eonBrdf's E_FON is eonDirectionalAlbedo, the polynomial fit of Eq. 14",
        "sampler: eonDirection (CLTC + uniform mixture) with eonPdf at the sampled wi, on the 'eonBrdf as eon' path",
    ]
    return Subject(
        name=PACKAGE,
        model="eon",
        brdf=brdf_of("eon"),
        brdf_domain=domain,
        sample=sample,
        pdf=pdf,
        notes=notes,
        paths=paths,
        **common,
    )
