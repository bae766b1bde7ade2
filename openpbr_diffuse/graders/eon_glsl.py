"""The EON paper authors' listings (portsmouth/EON-diffuse ``main.glsl``) run as GLSL.

Graded: the file's renderer-facing routines ``diffuse_brdf_evaluate`` and
``diffuse_brdf_albedo`` (which call Listing 1's ``f_EON`` / ``E_EON`` with ``exact = true``
after their horizon test, with albedo and roughness in the file's uniforms ``albedo`` and
``roughness``: one dispatch per distinct (roughness, rho)), and the sampler ``sample_EON`` /
``pdf_EON`` (Listings 2-4) called with the grader's uniform numbers.  The file leaves two helpers to
the host renderer, ``sqr`` and ``rand``: the wrapper supplies them (``rand`` only has to exist
for the file to compile; the grader passes its own uniform numbers to ``sample_EON``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import glsl
from ._arrays import rows
from .errors import GraderUnavailable
from .subject import Subject

FILES = ("main.glsl",)
HOST_PRELUDE = """
#define sqr(x) ((x)*(x))
float rand(inout uint seed) { seed = seed * 747796405u + 2891336453u; return float(seed >> 8) / 16777216.0; }
"""
TOLERANCE, TOLERANCE_REASON = glsl.TOLERANCE, glsl.TOLERANCE_REASON


def _read(source: Path) -> str:
    path = Path(source) / "main.glsl"
    if not path.is_file():
        raise GraderUnavailable(f"{source} does not hold the EON-diffuse listings (main.glsl): "
                                "pass --source PATH/TO/EON-diffuse (github.com/portsmouth/EON-diffuse)")
    return glsl.resolve_includes(path)


def by_material(kernel, inputs, roughness, rho, label):
    """Run ``kernel`` once per distinct (roughness, rho): the file reads them from uniforms."""
    n = inputs.shape[0]
    material = rows(np.broadcast_to(np.asarray(roughness, float).reshape(-1), (n,)),
                    np.broadcast_to(np.asarray(rho, float), (n, 3)))
    keys, group = np.unique(material, axis=0, return_inverse=True)
    out = np.zeros((n, kernel.n_out), np.float32)
    for k, key in enumerate(keys):
        sel = group.reshape(-1) == k
        kernel.uniforms = {"roughness": float(key[0]), "albedo": tuple(float(x) for x in key[1:])}
        out[sel] = kernel.run(inputs[sel], label)
    return out


def subject(source: Path) -> Subject:
    """The authors' GLSL listings found in the folder ``source`` (an EON-diffuse checkout)."""
    source = Path(source)
    code = _read(source)

    def kernel(body, n_in, n_out):
        return glsl.Kernel(code=code, body=body, n_in=n_in, n_out=n_out, preamble=HOST_PRELUDE)

    k_brdf = kernel("""
    vec3 wi = vec3(IN(0), IN(1), IN(2)); vec3 wo = vec3(IN(3), IN(4), IN(5)); float pdf = 0.0;
    vec3 f = diffuse_brdf_evaluate(wi, wo, pdf);
    OUT(0) = f.x; OUT(1) = f.y; OUT(2) = f.z;""", 6, 3)
    k_albedo = kernel("""
    float mu = IN(0); uint seed = 1u;
    vec3 E = diffuse_brdf_albedo(vec3(sqrt(max(0.0, 1.0 - mu*mu)), 0.0, mu), seed);
    OUT(0) = E.x; OUT(1) = E.y; OUT(2) = E.z;""", 1, 3)
    k_sample = kernel("""
    vec4 s = sample_EON(vec3(IN(0), IN(1), IN(2)), IN(3), IN(4), IN(5));
    OUT(0) = s.x; OUT(1) = s.y; OUT(2) = s.z; OUT(3) = s.w;""", 6, 4)
    k_pdf = kernel("""
    OUT(0) = pdf_EON(vec3(IN(0), IN(1), IN(2)), vec3(IN(3), IN(4), IN(5)), IN(6));""", 7, 1)
    label = f"{source / 'main.glsl'}"

    def brdf(wi, wo, roughness, rho):
        return by_material(k_brdf, rows(wi, wo), roughness, rho, label)

    def albedo(mu, roughness, rho):
        return by_material(k_albedo, rows(mu), roughness, rho, label)

    def sample(wo, roughness, u):
        out = k_sample.run(rows(wo, roughness, u), label)
        return out[:, :3], out[:, 3]

    def pdf(wo, wi, roughness):
        return k_pdf.run(rows(wo, wi, roughness), label)[:, 0]

    return Subject(
        name="eon-diffuse-glsl", model="eon", tolerance=TOLERANCE, tolerance_reason=TOLERANCE_REASON,
        version={"source": str(source.resolve()), "files": list(FILES),
                 "sha256": glsl.sources_hash([source / f for f in FILES]), "gl": glsl.gl_version()},
        brdf=brdf, albedo=albedo, sample=sample, pdf=pdf,
        notes=["f and E through the file's diffuse_brdf_evaluate / diffuse_brdf_albedo (f_EON / E_EON "
               "with exact = true behind a horizon test: directions with z < 1e-7 give 0)",
               "sampler: sample_EON / pdf_EON (Listings 2-4)"])
