"""Each export language: its prelude, its header, and the adapters to the graded signatures.

The functions themselves come from the one neutral source (:mod:`.render`); what is written
here per language is only what the neutral subset cannot say: the scalar and vector types,
the select helper ``eon_sel``, and wrappers taking the argument types ``openpbr-diffuse
check`` calls with (GLSL's ``vec2 u``, C++'s GLM types).
"""

from __future__ import annotations

from pathlib import Path

from .._version import __version__
from . import mtlx
from .constants import PRECISIONS, constants, literal
from .render import fill, neutral_source, render

#: the export languages (mtlx: a MaterialX nodedef and its genglsl implementation, two files)
LANGS = ("glsl", "wgsl", "cpp", "osl", "mtlx")
#: the languages with a double-precision export
DOUBLE = ("cpp",)

_CITATION = (
    'Portsmouth, Kutz, Hill, "EON: A practical energy-preserving rough diffuse BRDF", '
    "Journal of Computer Graphics Techniques (JCGT) 14(1), 2025"
)
_FUNCTIONS = "--function eon_f --albedo-function eon_albedo --sample-function eon_sample_wi --pdf-function eon_pdf --sampler-model eon"

#: what each export passed (its tests: tests/test_export.py), for the header
GRADES = {
    "glsl": (
        "passes `openpbr-diffuse check --glsl` on Mesa llvmpipe (float32): BRDF and albedo vectors of "
        "model eon, sampler (pdf normalisation, chi^2, validity) and pdf equal to the reference eon "
        "strategy's; finite at mu = 0, r = 0, rho = 0 and 1"
    ),
    "wgsl": (
        "passes `openpbr-diffuse check --wgsl` through wgpu on Mesa lavapipe (float32): BRDF and albedo "
        "vectors of model eon; and, run by the package's tests, f, the fit and white_tint variants, "
        "albedo and pdf against the library in float32; finite at mu = 0, r = 0, rho = 0 and 1"
    ),
    "cpp": (
        "passes `openpbr-diffuse check --cpp` (g++, GLM adapters) in float and double: BRDF and albedo "
        "vectors of model eon, sampler and pdf equal to the reference eon strategy's; finite at "
        "mu = 0, r = 0, rho = 0 and 1"
    ),
    "osl": (
        "compiled by the oslc of Blender's Cycles (bpy 5.0, OSL 1.14) and rendered through a Script node "
        "by the package's tests: f, the fit and white_tint variants, albedo and pdf against the library "
        "in float32; the shader eon_diffuse's f and albedo outputs at a known view"
    ),
    "mtlx": (
        "loaded and validated by MaterialX 1.39; the GLSL MaterialX's GlslShaderGenerator emits for a "
        "material using the node compiles on Mesa llvmpipe, and its EON functions, taken from that "
        "generated shader, pass `openpbr-diffuse check --glsl`"
    ),
}
#: the precision each export is tested to (relative to the library's float64 results, plus an absolute floor)
PRECISION_BOUNDS = {
    ("glsl", "float"): "2e-5 relative + 1e-6 absolute (float32 arithmetic of llvmpipe)",
    ("wgsl", "float"): "2e-5 relative + 1e-6 absolute (float32 arithmetic of lavapipe)",
    ("cpp", "float"): "2e-5 relative + 1e-6 absolute (float32, about 170 ulp)",
    ("cpp", "double"): "1e-12 relative + 1e-14 absolute (float64)",
    (
        "osl",
        "float",
    ): "2e-5 relative + 1e-6 absolute (float32 of Cycles' OSL on the CPU), 5x looser for its transcendental functions",
    ("mtlx", "float"): "that of the GLSL export (the same functions)",
}


def grade_command(lang: str, path: str = "FILE") -> str:
    """The ``openpbr-diffuse check`` command that grades the ``lang`` export at ``path``.

    Examples
    --------
    >>> grade_command("glsl").split()[:4]
    ['openpbr-diffuse', 'check', '--glsl', 'FILE']
    """
    if lang == "glsl":
        return f"openpbr-diffuse check --glsl {path} {_FUNCTIONS}"
    if lang == "cpp":
        return f"openpbr-diffuse check --cpp {path} --define EON_GLM=1 {_FUNCTIONS}"
    if lang == "wgsl":
        return f"openpbr-diffuse check --wgsl {path} --function eon_f --albedo-function eon_albedo"
    if lang == "osl":
        return "none: openpbr-diffuse check has no --osl"
    if lang == "mtlx":
        return "none: openpbr-diffuse check has no --mtlx (the GLSL functions are those of --lang glsl)"
    raise ValueError(f"lang: expected one of {', '.join(LANGS)}, got {lang!r}")


def _header(lang: str, precision: str) -> str:
    lines = [
        f"EON, the energy-preserving Oren-Nayar diffuse BRDF of OpenPBR ({lang}, {precision} precision):",
        "evaluation (exact E_F and the Eq. 14 fit; colour modes reference and white_tint), directional",
        "and average albedo (closed form, E = rho E_F + rho_ms (1 - E_F), for lobe selection), the sampler",
        "(CLTC + uniform, one-sample MIS, Listings 2-4) with its pdf, and the FON, QON and Lambert limits.",
        "",
        _CITATION + ".",
        "",
        "Conventions: local shading frame, normal +z; wi towards the light, wo towards the viewer, both",
        "pointing away from the surface; f without the cosine factor; roughness r in [0, 1] (QON: sigma",
        "in radians); rho linear RGB in [0, 1].  f = 0 when wi.z <= 0 or wo.z <= 0; finite at mu = 0.",
        "",
        f"Generated by openpbr-diffuse {__version__}: openpbr-diffuse export --lang {lang} --precision {precision}",
        "(regenerate rather than edit).  Licence: Apache-2.0 (SPDX-License-Identifier: Apache-2.0).",
        "Passed: " + GRADES[lang] + ".",
        "Precision against the library: " + PRECISION_BOUNDS[(lang, precision)] + ".",
    ]
    text = ""
    width = 100
    for line in lines:
        words, cur = line.split(" "), ""
        for w in words:  # wrap the long sentences
            if cur and len(cur) + 1 + len(w) > width:
                text += f"// {cur}\n"
                cur = w
            else:
                cur = f"{cur} {w}" if cur else w
        text += f"// {cur}".rstrip() + "\n"
    return text + f"// grade: {grade_command(lang)}\n"


_GLSL_PRELUDE = """
float eon_sel(bool c, float a, float b) { return c ? a : b; }
"""
_GLSL_ADAPTERS = """
// the sampler with u as a vec2 (the signature openpbr-diffuse check calls)
vec3 eon_sample_wi(vec3 wo, vec2 u, float roughness) { return eon_sample_wi(wo, u.x, u.y, roughness); }
"""
_WGSL_PRELUDE = """
fn eon_sel(c: bool, a: f32, b: f32) -> f32 { return select(b, a, c); }
"""
_CPP_PRELUDE = """
#ifndef EON_EXPORT_INCLUDED
#define EON_EXPORT_INCLUDED
#include <cmath>

// plain functions: host code, and CUDA / HIP device code
#ifndef EON_HOST_DEVICE
#if defined(__CUDACC__) || defined(__HIPCC__)
#define EON_HOST_DEVICE __host__ __device__
#else
#define EON_HOST_DEVICE
#endif
#endif

typedef REAL eon_real;
struct eon_vec3 {
    eon_real x, y, z;
};
EON_HOST_DEVICE inline eon_vec3 eon_vec3_make(eon_real x, eon_real y, eon_real z) {
    eon_vec3 v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}
EON_HOST_DEVICE inline eon_real eon_sel(bool c, eon_real a, eon_real b) { return c ? a : b; }
"""
_CPP_ADAPTERS = """
// The signatures openpbr-diffuse check calls (GLM, float), with -DEON_GLM=1.
#ifdef EON_GLM
#include <glm/glm.hpp>
inline eon_vec3 eon_from_glm(glm::vec3 v) { return eon_vec3_make(eon_real(v.x), eon_real(v.y), eon_real(v.z)); }
inline glm::vec3 eon_to_glm(eon_vec3 v) { return glm::vec3(float(v.x), float(v.y), float(v.z)); }
inline glm::vec3 eon_f(glm::vec3 wi, glm::vec3 wo, float roughness, glm::vec3 rho) {
    return eon_to_glm(eon_f(eon_from_glm(wi), eon_from_glm(wo), eon_real(roughness), eon_from_glm(rho)));
}
inline glm::vec3 eon_albedo(float mu, float roughness, glm::vec3 rho) {
    return eon_to_glm(eon_albedo(eon_real(mu), eon_real(roughness), eon_from_glm(rho)));
}
inline glm::vec3 eon_sample_wi(glm::vec3 wo, glm::vec2 u, float roughness) {
    return eon_to_glm(eon_sample_wi(eon_from_glm(wo), eon_real(u.x), eon_real(u.y), eon_real(roughness)));
}
inline float eon_pdf(glm::vec3 wo, glm::vec3 wi, float roughness) {
    return float(eon_pdf(eon_from_glm(wo), eon_from_glm(wi), eon_real(roughness)));
}
#endif

#endif  // EON_EXPORT_INCLUDED
"""
_OSL_PRELUDE = """
float eon_sel(int c, float a, float b) { return c ? a : b; }
"""
_OSL_SHADER = """
// The lobe at this shading point: f for the local light direction wi_local (the frame: N, the
// tangent from dPdu, and N x tangent; wo = -I in it), and the directional albedo at wo.
shader eon_diffuse(
    float roughness = 0.5,
    color rho = color(0.8),
    vector wi_local = vector(0, 0, 1),
    output color f_value = 0,
    output color albedo_value = 0)
{
    vector Z = normalize(N);
    vector T = dPdu - dot(dPdu, Z) * Z;
    vector X = length(T) > 0 ? normalize(T) : normalize(cross(Z, abs(Z[0]) < 0.9 ? vector(1, 0, 0) : vector(0, 1, 0)));
    vector Y = cross(Z, X);
    // I points from the viewer to the point (the OSL specification); Blender's Cycles passes the
    // reverse: on a front face the viewer is on the side of Ng, which settles it
    vector V = -normalize(I);
    if (!backfacing() && dot(V, Ng) < 0) {
        V = -V;
    }
    vector wo = vector(dot(V, X), dot(V, Y), dot(V, Z));
    vector r3 = vector(rho[0], rho[1], rho[2]);
    vector fv = eon_f(normalize(wi_local), wo, roughness, r3);
    vector av = eon_albedo(wo[2], roughness, r3);
    f_value = color(fv[0], fv[1], fv[2]);
    albedo_value = color(av[0], av[1], av[2]);
}
"""


def export_text(lang: str, precision: str = "float", *, glsl_file: str = "eon_genglsl.glsl") -> str:
    """The ``lang`` export ("glsl", "wgsl", "cpp", "osl" or "mtlx") in ``precision`` ("float"; "double" for cpp).

    For "mtlx" this is the ``.mtlx`` document, whose implementation names ``glsl_file``
    (:func:`export_files` gives both files).

    Examples
    --------
    >>> text = export_text("cpp", "double")
    >>> "typedef double eon_real;" in text, text.count("// grade: ")
    (True, 1)
    """
    if lang not in LANGS:
        raise ValueError(f"lang: expected one of {', '.join(LANGS)}, got {lang!r}")
    if precision not in PRECISIONS:
        raise ValueError(f"precision: expected float or double, got {precision!r}")
    if precision == "double" and lang not in DOUBLE:
        raise ValueError(f"precision: double is available for {', '.join(DOUBLE)} only ({lang} has float only)")
    values = {k: literal(v) for k, v in constants(precision).items()}
    body = render(fill(neutral_source(), values), "glsl" if lang == "mtlx" else lang, precision)
    head = _header(lang, precision)
    if lang == "glsl":
        return head + _GLSL_PRELUDE + "\n" + body + _GLSL_ADAPTERS
    if lang == "wgsl":
        return head + _WGSL_PRELUDE + "\n" + body
    if lang == "cpp":
        return head + _CPP_PRELUDE.replace("REAL", precision) + "\n" + body + _CPP_ADAPTERS
    if lang == "mtlx":
        return mtlx.document(head, glsl_file)
    return head + _OSL_PRELUDE + "\n" + body + _OSL_SHADER


def export_files(lang: str, path: str | Path, precision: str = "float") -> list[tuple[Path, str]]:
    """The files of the ``lang`` export written at ``path``: [(path, text)], two for "mtlx"
    (the document and ``NAME_genglsl.glsl`` beside it).

    Examples
    --------
    >>> [p.name for p, _ in export_files("mtlx", "out/eon.mtlx")]
    ['eon.mtlx', 'eon_genglsl.glsl']
    """
    path = Path(path)
    if lang != "mtlx":
        return [(path, export_text(lang, precision))]
    glsl_path = path.with_name(mtlx.glsl_name(path))
    if precision != "float":
        raise ValueError(f"precision: double is available for {', '.join(DOUBLE)} only ({lang} has float only)")
    values = {k: literal(v) for k, v in constants(precision).items()}
    body = render(fill(neutral_source(), values), "glsl", precision)
    glsl = mtlx.implementation_glsl(_header(lang, precision) + _GLSL_PRELUDE + "\n" + body + _GLSL_ADAPTERS)
    return [(path, export_text(lang, precision, glsl_file=glsl_path.name)), (glsl_path, glsl)]


__all__ = ["DOUBLE", "GRADES", "LANGS", "PRECISION_BOUNDS", "export_files", "export_text", "grade_command"]
