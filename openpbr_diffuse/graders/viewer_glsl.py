"""OpenPBR-viewer's path-tracing GLSL (``glsl/pathtracing/``), run on llvmpipe.

The viewer's files are concatenated in the order the viewer's path tracer uses them (``main.glsl``
with the uniforms and helpers first, the lobe files, ``openpbr_surface.glsl``; ``pathtracer.glsl``
— BVH traversal and the ``main()`` of the render — is left out).  Three lines of ``main.glsl``
only make sense inside three.js's WebGL pipeline and are dropped, by pattern, with nothing else
changed: the ``#include <three.js chunk>``, the ``uniform BVH`` declarations (three-mesh-bvh's
struct) and the ``varying`` declaration.  The material is set through the viewer's own uniforms
(``base_color``, ``base_diffuse_roughness``, ...).

Graded:

* BRDF: the diffuse lobe as the surface uses it, ``lobe weight colour x diffuse_brdf_evaluate``:
  ``diffuse_brdf_evaluate`` returns the EON value at white albedo and the surface multiplies its
  weight by ``base_color`` — so the grader returns ``rho * diffuse_brdf_evaluate(wi, wo)``.
* Albedo: ``rho * diffuse_brdf_albedo(wo)``, the same convention.
* Sampler: ``diffuse_brdf_sample`` (the viewer's own ``rand`` stream, seeded per row) and the pdf
  ``diffuse_brdf_evaluate`` reports.
* Surface: ``openpbr_prepare``'s ``lobe_weights``/``lobe_albedos``/``lobe_probs`` for the diffuse
  lobe (its specular albedo is a 4-sample Monte Carlo estimate, so the grader averages 256 seeds).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from . import glsl
from ._arrays import rows
from .errors import GraderUnavailable
from .subject import Subject

FILES = ("main.glsl", "thin-film.glsl", "specular_brdf.glsl", "specular_btdf.glsl", "metal_brdf.glsl",
         "coat_brdf.glsl", "fuzz_brdf.glsl", "diffuse_brdf.glsl", "diffuse_btdf.glsl",
         "openpbr_surface.glsl")
_WEBGL_ONLY = re.compile(r"^\s*(#include\s*<[^>]*>|uniform\s+BVH\s+\w+\s*;|varying\s+.*;)\s*$", re.M)
TOLERANCE, TOLERANCE_REASON = glsl.TOLERANCE, glsl.TOLERANCE_REASON
SURFACE_SEEDS = 256
MATERIAL_DEFAULTS = {  # the viewer's uniforms left at OpenPBR defaults for a plain dielectric
    "base_weight": 1.0, "base_color": (0.8, 0.8, 0.8), "base_diffuse_roughness": 0.0, "base_metalness": 0.0,
    "specular_weight": 1.0, "specular_color": (1.0, 1.0, 1.0), "specular_roughness": 0.3,
    "specular_anisotropy": 0.0, "specular_ior": 1.5, "transmission_weight": 0.0, "subsurface_weight": 0.0,
    "subsurface_color": (0.8, 0.8, 0.8), "coat_weight": 0.0, "coat_ior": 1.6, "fuzz_weight": 0.0,
    "thin_film_weight": 0.0, "geometry_opacity": 1.0, "geometry_thin_walled": False,
}


def folder(source: Path) -> Path:
    source = Path(source)
    for candidate in (source, source / "glsl" / "pathtracing", source / "pathtracing"):
        if all((candidate / f).is_file() for f in FILES):
            return candidate
    raise GraderUnavailable(f"{source} does not hold OpenPBR-viewer's glsl/pathtracing/ "
                            f"({', '.join(FILES[:3])}, ...): pass --source PATH/TO/OpenPBR-viewer")


def code(path: Path) -> str:
    return "\n".join(_WEBGL_ONLY.sub("", glsl.resolve_includes(path / f)) for f in FILES)


def subject(source: Path) -> Subject:
    """OpenPBR-viewer's diffuse lobe and surface, from a checkout at ``source``."""
    path = folder(source)
    text = code(path)
    # per row: basis from the +z normal, as the viewer builds it at a hit point
    head = "    Basis basis = makeBasis(vec3(0.0, 0.0, 1.0)); vec3 pW = vec3(0.0);\n"
    k_brdf = glsl.Kernel(code=text, n_in=9, n_out=3, body=head + """
    vec3 wi = vec3(IN(0), IN(1), IN(2)); vec3 wo = vec3(IN(3), IN(4), IN(5)); float pdf = 0.0;
    vec3 f = vec3(IN(6), IN(7), IN(8)) * diffuse_brdf_evaluate(pW, basis, wo, wi, pdf);
    OUT(0) = f.x; OUT(1) = f.y; OUT(2) = f.z;""")
    k_albedo = glsl.Kernel(code=text, n_in=4, n_out=3, body=head + """
    float mu = IN(0); uint seed = 1u;
    vec3 E = vec3(IN(1), IN(2), IN(3)) * diffuse_brdf_albedo(pW, basis, vec3(sqrt(max(0.0, 1.0 - mu*mu)), 0.0, mu), seed);
    OUT(0) = E.x; OUT(1) = E.y; OUT(2) = E.z;""")
    k_sample = glsl.Kernel(code=text, n_in=4, n_out=4, body=head + """
    uint seed = floatBitsToUint(IN(3)); vec3 wi = vec3(0.0); float pdf = 0.0;
    rand(seed);
    diffuse_brdf_sample(pW, basis, vec3(IN(0), IN(1), IN(2)), seed, wi, pdf);
    OUT(0) = wi.x; OUT(1) = wi.y; OUT(2) = wi.z; OUT(3) = pdf;""")
    k_pdf = glsl.Kernel(code=text, n_in=6, n_out=1, body=head + """
    float pdf = 0.0;
    diffuse_brdf_evaluate(pW, basis, vec3(IN(0), IN(1), IN(2)), vec3(IN(3), IN(4), IN(5)), pdf);
    OUT(0) = pdf;""")
    k_surface = glsl.Kernel(code=text, n_in=4, n_out=4, body=head + """
    uint seed = floatBitsToUint(IN(3)); rand(seed);
    openpbr_prepare(pW, basis, vec3(IN(0), IN(1), IN(2)), seed);
    vec3 wE = lobe_weights.m[ID_DIFF_BRDF] * lobe_albedos.m[ID_DIFF_BRDF];
    OUT(0) = wE.x; OUT(1) = wE.y; OUT(2) = wE.z; OUT(3) = lobe_probs.m[ID_DIFF_BRDF];""")
    label = str(path)

    def by_roughness(kernel, roughness, inputs, extra=None):
        """The viewer takes roughness from a uniform: one dispatch per distinct value."""
        roughness = np.asarray(roughness, dtype=np.float32).reshape(-1)
        out = np.zeros((inputs.shape[0], kernel.n_out), np.float32)
        for r in np.unique(roughness):
            sel = roughness == r
            kernel.uniforms = {**_uniforms(MATERIAL_DEFAULTS), "base_diffuse_roughness": float(r), **(extra or {})}
            out[sel] = kernel.run(inputs[sel], label)
        return out

    def brdf(wi, wo, roughness, rho):
        # the viewer's convention: winputL is the known (camera-side) direction, woutputL the other
        return by_roughness(k_brdf, roughness, rows(wi, wo, rho))

    def albedo(mu, roughness, rho):
        return by_roughness(k_albedo, roughness, rows(mu, rho))

    def sample(wo, roughness, u):
        # the viewer draws its own numbers with its rand(); u only seeds it (one seed per row)
        seeds = (np.arange(len(wo), dtype=np.uint32) * np.uint32(2654435761)
                 + (np.asarray(u)[:, 0] * 2**32).astype(np.uint64).astype(np.uint32))
        inputs = np.concatenate([rows(wo), seeds.view(np.float32)[:, None]], axis=1)
        out = by_roughness(k_sample, roughness, inputs)
        return out[:, :3], out[:, 3]

    def pdf(wo, wi, roughness):
        return by_roughness(k_pdf, roughness, rows(wo, wi))[:, 0]

    def surface(inputs, wo):
        wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)
        n = wo.shape[0]
        material = {**MATERIAL_DEFAULTS, **inputs}
        seeds = (np.arange(n * SURFACE_SEEDS, dtype=np.uint32) * np.uint32(2654435761) + np.uint32(12345))
        data = np.concatenate([np.repeat(rows(wo), SURFACE_SEEDS, axis=0), seeds.view(np.float32)[:, None]], axis=1)
        k_surface.uniforms = _uniforms(material)
        out = k_surface.run(data, label).reshape(n, SURFACE_SEEDS, 4).astype(np.float64).mean(axis=1)
        return {"weight_albedo": out[:, :3], "probability": out[:, 3]}

    return Subject(
        selection="length",
        name="openpbr-viewer-glsl", model="eon", tolerance=TOLERANCE, tolerance_reason=TOLERANCE_REASON,
        version={"source": str(path.resolve()), "files": list(FILES),
                 "sha256": glsl.sources_hash([path / f for f in FILES]), "gl": glsl.gl_version()},
        brdf=brdf, albedo=albedo, sample=sample, pdf=pdf, surface=surface,
        notes=["BRDF/albedo = base_color x the white-albedo lobe, as openpbr_surface.glsl weights it",
               f"surface quantities averaged over {SURFACE_SEEDS} seeds (4-sample MC specular albedo); "
               "selection by |w E| length"])


def _uniforms(material: dict) -> dict:
    out = {}
    for k, v in material.items():
        out[k] = tuple(float(x) for x in v) if isinstance(v, (tuple, list, np.ndarray)) else v
    return out
