"""three.js (npm ``three``): its EON diffuse lobe as ``MeshPhysicalMaterial``'s GLSL computes it.

three.js (r187 and later) ships EON in the GLSL shader chunk ``lights_physical_pars_fragment``
(``src/renderers/shaders/ShaderChunk/lights_physical_pars_fragment.glsl.js``, a JavaScript module
whose default export is the GLSL text), inside ``#ifdef USE_DIFFUSE_ROUGHNESS``:
``BRDF_EON(lightDir, viewDir, normal, diffuseColor, roughness)`` and
``EON_DirectionalAlbedo(diffuseColor, roughness, dotNV)``, both with ``FON_DirectionalAlbedo``,
the polynomial fit of E_FON (Eq. 14 of Portsmouth et al. 2025).  The grader reads the chunk and
the ``common`` chunk (``PI``, ``RECIPROCAL_PI``, ``saturate``, ``BRDF_Lambert``) out of the
installed package at run time -- through ``node``, which imports the modules, so the text is
exactly what the renderer registers -- takes the ``USE_DIFFUSE_ROUGHNESS`` block and runs it on
llvmpipe (:mod:`.glsl`).  Nothing of three.js's source is kept in this project.

How the renderer calls them (statements of the installed chunk the harness replays, checked
present, :data:`EXPECTED`):

- direct lights (``RE_Direct_Physical``): ``irradiance = saturate(dot(N, L)) * color`` and
  ``directDiffuse += irradiance * BRDF_EON(L, V, N, diffuseColor, roughness) * (1 - metalness)
  * (1 - F)``.  The harness returns ``saturate(N.L) * BRDF_EON(...)`` for a light of colour 1,
  metalness 0 and no specular layer (F = 0), divided by the same ``saturate(N.L)``: f above the
  horizon and 0 below it.  ``BRDF_EON`` alone is not 0 below the horizon (it clamps N.L to 0 and
  returns the lobe there); :func:`function_values` runs it bare, for that comparison;
- environment and ambient light (``RE_IndirectDiffuse_Physical``): ``irradiance / pi *
  EON_DirectionalAlbedo(diffuseColor, roughness, saturate(N.V))``: the directional albedo.

Both are graded twice, as two paths: as ``eon`` (what the chunk's comment cites) and as
``eon_approx`` (EON with the Eq. 14 fit of E_FON).  The WebGPU renderer's TSL node
(``src/nodes/functions/BSDF/BRDF_EON.js``) builds its shader from JavaScript at run time and is
not graded here.
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import glsl
from ._arrays import rows
from .babylon import CACHE_VARIABLE, installed_package, package_info, package_version, require_node, run_node
from .errors import GraderUnavailable
from .subject import Subject

PACKAGE = "three"
INSTALL = (
    f"install it with: npm install --prefix ~/.cache/openpbr-diffuse/npm {PACKAGE} "
    f"(or set ${CACHE_VARIABLE} to the --prefix folder you used); Debian: apt-get install nodejs npm"
)
#: the chunk modules read, in the order the harness concatenates them
CHUNK_FOLDER = "src/renderers/shaders/ShaderChunk"
CHUNKS = ("common", "lights_physical_pars_fragment")
#: the block of ``lights_physical_pars_fragment`` that holds the lobe
BLOCK = "USE_DIFFUSE_ROUGHNESS"
#: statements of the installed chunk the harness replays (compared without white space); a missing
#: one means the harness is out of date for that version, and the grader refuses to run
EXPECTED = (
    "float dotNL = saturate( dot( geometryNormal, directLight.direction ) );",
    "vec3 irradiance = dotNL * directLight.color;",
    "vec3 diffuseBRDF = BRDF_EON( directLight.direction, geometryViewDir, geometryNormal, "
    "material.diffuseColor, material.diffuseRoughness ) * ( 1.0 - material.metalness );",
    "reflectedLight.directDiffuse += irradiance * diffuseBRDF * ( 1.0 - F );",
    "float dotNV = saturate( dot( geometryNormal, geometryViewDir ) );",
    "vec3 diffuseAlbedo = EON_DirectionalAlbedo( material.diffuseColor, material.diffuseRoughness, dotNV )",
)
TOLERANCE, TOLERANCE_REASON = glsl.TOLERANCE, glsl.TOLERANCE_REASON
#: (label, model) of the paths: the same code graded as each model
PATHS = (("as eon", "eon"), ("as eon_approx", "eon_approx"))

_EXTRACT = """
import { pathToFileURL } from "url";
import { readFileSync } from "fs";
const files = JSON.parse(readFileSync(0, "utf8"));
const out = {};
for (const [name, f] of Object.entries(files)) {
  const m = await import(pathToFileURL(f).href);
  if (typeof m.default !== "string") throw new Error(f + ": no GLSL string as default export");
  out[name] = m.default;
}
process.stdout.write(JSON.stringify(out));
"""

# RE_Direct_Physical for one directional light of colour 1 along L (metalness 0, F = 0); the bare
# call next to it for function_values()
_BRDF_BODY = """
    vec3 L = vec3(IN(0), IN(1), IN(2)); vec3 V = vec3(IN(3), IN(4), IN(5)); vec3 N = vec3(0.0, 0.0, 1.0);
    float r = IN(6); vec3 diffuseColor = vec3(IN(7), IN(8), IN(9));
    float dotNL = saturate( dot( N, L ) );
    vec3 irradiance = dotNL * vec3(1.0);
    vec3 d = irradiance * BRDF_EON( L, V, N, diffuseColor, r );
    vec3 bare = BRDF_EON( L, V, N, diffuseColor, r );
    OUT(0) = d.x; OUT(1) = d.y; OUT(2) = d.z; OUT(3) = dotNL; OUT(4) = bare.x; OUT(5) = bare.y; OUT(6) = bare.z;"""
# RE_IndirectDiffuse_Physical's albedo for a view direction at cosine mu
_ALBEDO_BODY = """
    float mu = IN(0); vec3 V = vec3(sqrt(max(0.0, 1.0 - mu*mu)), 0.0, mu); vec3 N = vec3(0.0, 0.0, 1.0);
    float dotNV = saturate( dot( N, V ) );
    vec3 a = EON_DirectionalAlbedo( vec3(IN(2), IN(3), IN(4)), IN(1), dotNV );
    OUT(0) = a.x; OUT(1) = a.y; OUT(2) = a.z;"""


def package_folder(prefix: Path | str | None = None) -> Path:
    """``node_modules/three`` under ``prefix`` (default: the project's npm cache), checked.

    ``prefix`` may also be the package folder itself.  Raises GraderUnavailable (with the
    install command) when the package is not there.

    >>> (package_folder() / CHUNK_FOLDER / "common.glsl.js").is_file()
    True
    """
    return installed_package(prefix, PACKAGE, lambda folder: (folder / CHUNK_FOLDER).is_dir(), INSTALL)


def chunk_files(folder: Path) -> list[Path]:
    """The chunk modules read (:data:`CHUNKS`), as paths inside ``folder``.

    >>> [p.name for p in chunk_files(package_folder())]
    ['common.glsl.js', 'lights_physical_pars_fragment.glsl.js']
    """
    return [Path(folder) / CHUNK_FOLDER / f"{name}.glsl.js" for name in CHUNKS]


@lru_cache(maxsize=4)
def chunks(folder: Path) -> dict[str, str]:
    """The GLSL text of :data:`CHUNKS` as the installed modules export it (read through node).

    >>> "vec3 BRDF_EON(" in chunks(package_folder())["lights_physical_pars_fragment"]
    True
    """
    require_node(f"{PACKAGE}'s shader chunks")
    files = dict(zip(CHUNKS, map(str, chunk_files(folder))))
    for name, f in files.items():
        if not Path(f).is_file():
            raise GraderUnavailable(
                f"{f}: no shader chunk {name} in {PACKAGE} {package_version(folder)} (the grader knows r187's layout)"
            )
    return dict(run_node(_EXTRACT, files, f"{PACKAGE}'s shader chunks"))


def _squash(text: str) -> str:
    return re.sub(r"\s+", "", text)


def eon_block(text: str) -> str:
    """The ``#ifdef USE_DIFFUSE_ROUGHNESS`` ... ``#endif`` block of ``text`` that defines ``BRDF_EON``.

    >>> eon_block("x\\n#ifdef USE_DIFFUSE_ROUGHNESS\\n#if A\\n#endif\\nvec3 BRDF_EON();\\n#endif\\ny")
    '#ifdef USE_DIFFUSE_ROUGHNESS\\n#if A\\n#endif\\nvec3 BRDF_EON();\\n#endif'
    """
    lines = text.splitlines()
    at = next((k for k, line in enumerate(lines) if "vec3 BRDF_EON(" in line), None)
    starts = [k for k, line in enumerate(lines[: at or 0]) if line.strip() == f"#ifdef {BLOCK}"]
    if at is None or not starts:
        raise GraderUnavailable(
            f"{PACKAGE}: no #ifdef {BLOCK} block defining BRDF_EON in lights_physical_pars_fragment"
        )
    depth = 0
    for k in range(starts[-1], len(lines)):
        word = lines[k].strip().split(" ")[0]
        depth += word in ("#if", "#ifdef", "#ifndef")
        depth -= word == "#endif"
        if depth == 0:
            return "\n".join(lines[starts[-1] : k + 1])
    raise GraderUnavailable(f"{PACKAGE}: the #ifdef {BLOCK} block around BRDF_EON has no #endif")


def source(folder: Path) -> str:
    """The GLSL the harness compiles: the ``common`` chunk and the EON block, ``USE_DIFFUSE_ROUGHNESS`` set.

    Raises GraderUnavailable when a statement of :data:`EXPECTED` is missing from the chunk.

    >>> "FON_DirectionalAlbedo" in source(package_folder())
    True
    """
    text = chunks(Path(folder))
    physical = _squash(text["lights_physical_pars_fragment"])
    missing = [s for s in EXPECTED if _squash(s) not in physical]
    if missing:
        raise GraderUnavailable(
            f"{PACKAGE} {package_version(folder)}: lights_physical_pars_fragment no longer holds "
            f"{missing[0]!r}: the harness replays r187's calls and would grade something else"
        )
    return f"#define {BLOCK}\n" + text["common"] + "\n" + eon_block(text["lights_physical_pars_fragment"])


@lru_cache(maxsize=4)
def _kernels(folder: Path) -> tuple[glsl.Kernel, glsl.Kernel]:
    code = source(folder)
    return (
        glsl.Kernel(code=code, n_in=10, n_out=7, body=_BRDF_BODY),
        glsl.Kernel(code=code, n_in=5, n_out=3, body=_ALBEDO_BODY),
    )


def _run_brdf(folder: Path, wi: ArrayLike, wo: ArrayLike, roughness: ArrayLike, rho: ArrayLike) -> np.ndarray:
    label = f"three.js {package_version(folder)} (BRDF_EON)"
    return _kernels(folder)[0].run(rows(wi, wo, roughness, rho), label).astype(np.float64)


def function_values(
    wi: ArrayLike, wo: ArrayLike, roughness: ArrayLike, rho: ArrayLike, folder: Path | None = None
) -> np.ndarray:
    """``BRDF_EON(wi, wo, +z, rho, roughness)`` called bare (no N.L factor around it): (n, 3).

    Not zero below the horizon: the function clamps N.L to 0 and returns the lobe there; the
    renderer multiplies it by ``saturate(N.L)`` (:func:`subject` grades it that way).

    >>> f = function_values(np.array([[0.6, 0.0, -0.8]]), np.array([[0.0, 0.0, 1.0]]),
    ...                     np.array([0.0]), np.array([[0.5, 0.5, 0.5]]))
    >>> bool(np.allclose(f, 0.5 / np.pi))     # roughness 0: rho/pi, below the horizon too
    True
    """
    folder = package_folder() if folder is None else Path(folder)
    return _run_brdf(folder, wi, wo, roughness, rho)[:, 4:7]


def subject(source_folder: Path | None = None) -> Subject:
    """three.js: one Subject whose ``paths`` grade the same code as ``eon`` and as ``eon_approx``.

    ``source_folder`` is an npm prefix or a ``three`` package folder (default: the project's npm
    cache).  The top-level callables are the direct light's f (``saturate(N.L) * BRDF_EON``
    divided by ``saturate(N.L)``; 0 below the horizon) and ``EON_DirectionalAlbedo``.

    >>> s = subject()
    >>> [label for label, _ in s.paths], s.model
    (['as eon', 'as eon_approx'], 'eon')
    >>> f = s.brdf(np.array([[0.0, 0.0, 1.0]]), np.array([[0.6, 0.0, 0.8]]), np.array([0.0]),
    ...            np.array([[0.5, 0.5, 0.5]]))
    >>> bool(np.allclose(f, 0.5 / np.pi, rtol=1e-6))    # roughness 0: Lambert
    True
    """
    folder = package_folder(source_folder)
    version = package_version(folder)
    source(folder)  # the expected statements, checked before anything runs
    info = package_info("three", folder, [str(p.relative_to(folder)) for p in chunk_files(folder)])

    def brdf(wi, wo, roughness, rho):
        out = _run_brdf(folder, wi, wo, roughness, rho)
        above = out[:, 3] > 0
        f = out[:, :3].copy()  # 0 below the horizon (saturate(N.L) = 0 times the lobe)
        f[above] /= out[above, 3:4]
        return f

    def domain(wi, wo):
        # the viewer's side: three.js clamps N.V with saturate (a back face is shaded with its
        # flipped normal); rows with mu_o <= 0 are outside what it renders
        return np.asarray(wo)[:, 2] > 0

    def albedo(mu, roughness, rho):
        label = f"three.js {version} (EON_DirectionalAlbedo)"
        return _kernels(folder)[1].run(rows(mu, roughness, rho), label).astype(np.float64)

    notes = [
        "direct light: saturate(N.L) * BRDF_EON(L, V, N, rho, r) as RE_Direct_Physical computes it (light "
        "colour 1, metalness 0, F = 0), divided by saturate(N.L): 0 below the horizon; BRDF_EON alone "
        "returns the lobe at N.L = 0 there",
        "albedo: EON_DirectionalAlbedo(rho, r, saturate(N.V)) as RE_IndirectDiffuse_Physical calls it",
        "E_FON: FON_DirectionalAlbedo, the polynomial fit of Eq. 14, in both",
    ]
    common: dict[str, Any] = {"tolerance": TOLERANCE, "tolerance_reason": TOLERANCE_REASON, "version": info}
    paths = [
        (label, Subject(name=f"threejs {label}", model=model, brdf=brdf, brdf_domain=domain, albedo=albedo, **common))
        for label, model in PATHS
    ]
    return Subject(
        name="threejs",
        model="eon",
        brdf=brdf,
        brdf_domain=domain,
        albedo=albedo,
        notes=[f"npm {PACKAGE} {version}: {CHUNK_FOLDER}/lights_physical_pars_fragment.glsl.js"] + notes,
        paths=paths,
        **{**common, "version": {**info, "gl": glsl.gl_version()}},
    )
