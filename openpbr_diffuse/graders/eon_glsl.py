"""The EON paper authors' listings (portsmouth/EON-diffuse ``main.glsl``) run as GLSL.

Graded: ``f_EON(rho, r, wi, wo, exact=true)`` (Listing 1), ``E_EON(rho, r, wo, exact=true)``,
and the sampler ``sample_EON`` / ``pdf_EON`` (Listings 2-4).  The file leaves two helpers to
the host renderer, ``sqr`` and ``rand``: the wrapper supplies them (``rand`` only has to exist
for the file to compile; the grader passes its own uniform numbers to ``sample_EON``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import glsl
from ._arrays import direction, rows
from .errors import GraderUnavailable
from .subject import Subject

FILES = ("main.glsl",)
HOST_PRELUDE = """
#define sqr(x) ((x)*(x))
float rand(inout uint seed) { seed = seed * 747796405u + 2891336453u; return float(seed >> 8) / 16777216.0; }
"""
TOLERANCE = 2e-4
TOLERANCE_REASON = ("GLSL on llvmpipe: float32 and llvmpipe's acos approximation (max abs error "
                    "1.6e-4 in the angle, entering E_F through G_F)")


def _read(source: Path) -> str:
    path = Path(source) / "main.glsl"
    if not path.is_file():
        raise GraderUnavailable(f"{source} does not hold the EON-diffuse listings (main.glsl): "
                                "pass --source PATH/TO/EON-diffuse (github.com/portsmouth/EON-diffuse)")
    return glsl.resolve_includes(path)


def subject(source: Path) -> Subject:
    """The authors' GLSL listings found in the folder ``source`` (an EON-diffuse checkout)."""
    source = Path(source)
    code = _read(source)

    def kernel(body, n_in, n_out):
        return glsl.Kernel(code=code, body=body, n_in=n_in, n_out=n_out, preamble=HOST_PRELUDE)

    k_brdf = kernel("""
    vec3 wi = vec3(IN(0), IN(1), IN(2)); vec3 wo = vec3(IN(3), IN(4), IN(5));
    vec3 f = f_EON(vec3(IN(7), IN(8), IN(9)), IN(6), wi, wo, true);
    OUT(0) = f.x; OUT(1) = f.y; OUT(2) = f.z;""", 10, 3)
    k_albedo = kernel("""
    float mu = IN(0);
    vec3 E = E_EON(vec3(IN(2), IN(3), IN(4)), IN(1), vec3(sqrt(max(0.0, 1.0 - mu*mu)), 0.0, mu), true);
    OUT(0) = E.x; OUT(1) = E.y; OUT(2) = E.z;""", 5, 3)
    k_sample = kernel("""
    vec4 s = sample_EON(vec3(IN(0), IN(1), IN(2)), IN(3), IN(4), IN(5));
    OUT(0) = s.x; OUT(1) = s.y; OUT(2) = s.z; OUT(3) = s.w;""", 6, 4)
    k_pdf = kernel("""
    OUT(0) = pdf_EON(vec3(IN(0), IN(1), IN(2)), vec3(IN(3), IN(4), IN(5)), IN(6));""", 7, 1)
    label = f"{source / 'main.glsl'}"

    def brdf(wi, wo, roughness, rho):
        return k_brdf.run(rows(wi, wo, roughness, rho), label)

    def albedo(mu, roughness, rho):
        return k_albedo.run(rows(mu, roughness, rho), label)

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
        notes=["f_EON/E_EON called with exact = true (Listing 1's analytic E_F)"])
