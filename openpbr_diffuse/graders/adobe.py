"""Adobe's OpenPBR BSDF (header-only C++, ``openpbr.h``), run through a compiled harness.

Graded, by calling its own functions:

* BRDF: its diffuse lobe ``OpenPBR_EnergyConservingRoughDiffuseLobe`` (``openpbr_initialize_lobe``
  + ``openpbr_calculate_lobe_value``), set up with an index-matched specular layer (eta = 1,
  alpha = 1), where its specular energy-compensation factors are exactly 1, and divided by the
  cosine its value includes.  The lobe calls ``openpbr_f_EON(..., Exact = false)`` (the Eq. 14
  fit of E_F), so the reference model is ``eon_approx``.  The lobe requires a view direction
  face-forwarded to the normal (``OPENPBR_ASSERT(cos_in >= 0)``): rows with wo below the horizon
  are outside its input domain and are not graded.
* Sampler: its diffuse lobe's ``openpbr_sample_lobe`` / ``openpbr_calculate_lobe_pdf``.
* Surface: for a material given as OpenPBR inputs and a view direction, the diffuse part of
  ``openpbr_eval`` integrated over light directions (the diffuse lobe's weight x albedo) and the
  diffuse lobe's selection probability ``lobe_weights[diffuse] / total`` of its aggregate lobe.

The implementation has no function for the diffuse lobe's directional albedo on its own.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import cpp
from ._arrays import rows
from .errors import GraderUnavailable
from .subject import Subject

HEADER = "openpbr.h"
TOLERANCE = None
TOLERANCE_REASON = ("compiled C++ in float32 with libm acos: the same float32 rounding that "
                    "conformance.grade's default tolerance is derived for")
MATERIAL_INPUTS = ("base_color", "base_diffuse_roughness", "base_metalness", "specular_roughness",
                   "specular_ior")

PRELUDE = """
#include <glm/glm.hpp>
#include "openpbr.h"
"""
# Material rows: base_color (3), base_diffuse_roughness, base_metalness, specular_roughness,
# specular_ior, then the view direction (3).
_MATERIAL = """
    OpenPBR_ResolvedInputs inputs = openpbr_make_default_resolved_inputs();
    inputs.base_color = vec3(in[0], in[1], in[2]);
    inputs.base_diffuse_roughness = in[3];
    inputs.base_metalness = in[4];
    inputs.specular_roughness = in[5];
    inputs.specular_ior = in[6];
    const vec3 view = normalize(vec3(in[7], in[8], in[9]));
    const OpenPBR_PreparedBsdf prepared = openpbr_prepare(inputs, vec3(1.0f), OpenPBR_BaseRgbWavelengths_nm,
                                                          OpenPBR_VacuumIor, view);
    const OpenPBR_AggregateLobe& base = prepared.fuzz_lobe.coating_lobe.base_lobe;
"""
ENTRIES = {
    # wi (3), wo (3), roughness, rho (3) -> f (3), the specular compensation factors (2)
    "brdf": cpp.Entry(10, 5, """
    OpenPBR_EnergyConservingRoughDiffuseLobe lobe;
    const vec3 light = vec3(in[0], in[1], in[2]), view = vec3(in[3], in[4], in[5]);
    openpbr_initialize_lobe(lobe, vec3(0.0f, 0.0f, 1.0f), view, vec3(in[7], in[8], in[9]), in[6], 1.0f, 1.0f);
    const OpenPBR_DiffuseSpecular v = openpbr_calculate_lobe_value(lobe, view, light);
    const vec3 f = light.z > 0.0f ? v.diffuse / light.z : v.diffuse;
    out[0] = f.x; out[1] = f.y; out[2] = f.z;
    out[3] = lobe.cached_specular_energy_compensation;
    out[4] = openpbr_look_up_opaque_dielectric_energy_complement(1.0f, 1.0f, max(light.z, 0.0f));"""),
    # diffuse lobe on its own: wo (3), roughness, u (2) -> wi (3), pdf
    "sample": cpp.Entry(6, 4, """
    OpenPBR_EnergyConservingRoughDiffuseLobe lobe;
    const vec3 view = vec3(in[0], in[1], in[2]);
    openpbr_initialize_lobe(lobe, vec3(0.0f, 0.0f, 1.0f), view, vec3(1.0f), in[3], 0.3f, 1.5f);
    vec3 light; OpenPBR_DiffuseSpecular weight; float pdf = 0.0f; OpenPBR_BsdfLobeType type;
    if (openpbr_sample_lobe(lobe, vec3(in[4], in[5], 0.5f), view, light, weight, pdf, type)) {
        out[0] = light.x; out[1] = light.y; out[2] = light.z; out[3] = pdf; }"""),
    "pdf": cpp.Entry(7, 1, """
    OpenPBR_EnergyConservingRoughDiffuseLobe lobe;
    const vec3 view = vec3(in[0], in[1], in[2]);
    openpbr_initialize_lobe(lobe, vec3(0.0f, 0.0f, 1.0f), view, vec3(1.0f), in[6], 0.3f, 1.5f);
    out[0] = openpbr_calculate_lobe_pdf(lobe, view, vec3(in[3], in[4], in[5]));"""),
    # material (10) + light (3) -> diffuse part of openpbr_eval (f * cos, 3)
    "surface_eval": cpp.Entry(13, 3, _MATERIAL + """
    const OpenPBR_DiffuseSpecular v = openpbr_eval(prepared, vec3(in[10], in[11], in[12]));
    out[0] = v.diffuse.x; out[1] = v.diffuse.y; out[2] = v.diffuse.z;"""),
    # material (10) -> diffuse selection probability, as openpbr_select_lobe weighs the lobes
    "surface_probability": cpp.Entry(10, 1, _MATERIAL + """
    float u = 0.5f, selected = 0.0f, total = 0.0f;
    openpbr_select_lobe(base, u, selected, total);
    out[0] = total > 0.0f ? base.lobe_weights[OpenPBR_DiffuseLobeIndex] / total : 0.0f;"""),
}


def harness(source: Path, include_dirs=()) -> cpp.Harness:
    source = Path(source)
    if not (source / HEADER).is_file() or not (source / "impl" / "openpbr_diffuse_lobe.h").is_file():
        raise GraderUnavailable(f"{source} does not hold Adobe's OpenPBR BSDF ({HEADER}, impl/): pass "
                                "--source PATH/TO/openpbr-bsdf (github.com/adobe/openpbr-bsdf)")
    files = sorted(p for p in source.rglob("*.h"))
    return cpp.Harness(prelude=PRELUDE, entries=ENTRIES, include_dirs=[str(source), *map(str, include_dirs)],
                       sources=files, label=f"{source / HEADER}")


def _gauss_hemisphere(n_theta=24, n_phi=48):
    """Gauss-Legendre in cos(theta) x midpoint in phi over the upper hemisphere: (dirs, weights)."""
    x, w = np.polynomial.legendre.leggauss(n_theta)
    mu, wmu = 0.5 * (x + 1.0), 0.5 * w
    phi = (np.arange(n_phi) + 0.5) * (2.0 * np.pi / n_phi)
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - M * M)
    dirs = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
    weights = (wmu[:, None] * np.full(n_phi, 2.0 * np.pi / n_phi)).reshape(-1)
    return dirs, weights


def subject(source: Path, include_dirs=()) -> Subject:
    """Adobe's OpenPBR BSDF found in ``source`` (a checkout of adobe/openpbr-bsdf)."""
    h = harness(source, include_dirs)
    h.binary()  # compile now: a missing compiler / GLM is reported before any grading starts

    def brdf(wi, wo, roughness, rho):
        out = h.run("brdf", rows(wi, wo, roughness, rho))
        if not np.all(out[:, 3:] == 1.0):  # the set-up must make the specular factors vanish
            raise GraderUnavailable("adobe-openpbr-bsdf: the specular compensation at eta = 1 is not 1 "
                                    "in this version; the diffuse lobe cannot be isolated")
        return out[:, :3]

    def brdf_domain(wi, wo):
        return np.asarray(wo)[:, 2] >= 0.0

    def sample(wo, roughness, u):
        out = h.run("sample", rows(wo, roughness, u))
        return out[:, :3], out[:, 3]

    def pdf(wo, wi, roughness):
        return h.run("pdf", rows(wo, wi, roughness))[:, 0]

    def surface(inputs, wo):
        wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)
        n = wo.shape[0]
        mat = rows(np.broadcast_to(inputs.get("base_color", (0.8, 0.8, 0.8)), (n, 3)),
                   np.full(n, inputs.get("base_diffuse_roughness", 0.0)), np.full(n, inputs.get("base_metalness", 0.0)),
                   np.full(n, inputs.get("specular_roughness", 0.3)), np.full(n, inputs.get("specular_ior", 1.5)), wo)
        dirs, weights = _gauss_hemisphere()
        m = dirs.shape[0]
        per_light = h.run("surface_eval", np.concatenate(
            [np.repeat(mat, m, axis=0), np.tile(dirs.astype(np.float32), (n, 1))], axis=1))
        # the diffuse part of eval is w * f * cos(theta_light): its integral is the weighted albedo
        weighted_albedo = np.einsum("nmc,m->nc", per_light.reshape(n, m, 3).astype(np.float64), weights)
        return {"weight_albedo": weighted_albedo,
                "probability": h.run("surface_probability", mat)[:, 0].astype(np.float64)}

    src = Path(source)
    return Subject(
        selection="max",
        name="adobe-openpbr-bsdf", model="eon_approx", tolerance=TOLERANCE, tolerance_reason=TOLERANCE_REASON,
        version={"source": str(src.resolve()), "files": len(h.sources),
                 "sha256": _tree_hash(h.sources, src), "compiler": cpp.compiler_version()},
        brdf=brdf, sample=sample, pdf=pdf, surface=surface, brdf_domain=brdf_domain,
        notes=["BRDF graded against eon_approx: the diffuse lobe calls openpbr_f_EON with Exact = false",
               "rows with wo below the horizon are outside the lobe's domain (face-forwarded view)",
               "no directional-albedo function for the diffuse lobe; surface selection uses max component "
               "(selection='max')"])


def _tree_hash(files, root):
    import hashlib
    h = hashlib.sha256()
    for f in files:
        h.update(str(Path(f).relative_to(root)).encode())
        h.update(Path(f).read_bytes())
    return h.hexdigest()
