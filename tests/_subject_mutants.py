"""Mutants of the conforming test subjects (tests/subjects/eon_conforming.glsl and .cpp).

Each mutant is the conforming source with a few small text edits that put in one common bug
the way renderer code gets it wrong (a 1/pi dropped, the cosine folded in, the roughness
squared, ...).  The edits are written once, in GLSL, and carried over to the C++ subject by
:func:`to_cpp` (GLM / std names, float literals); where the two languages differ an edit gives
its C++ text explicitly.  Every edit must match the conforming source exactly ``count`` times,
so a change of the subjects cannot silently turn a mutant into the conforming code.

:func:`batch_subjects` puts every mutant into ONE shader (GLSL, llvmpipe) or ONE compiled
harness (C++, g++), their identifiers renamed per mutant, behind a dispatcher on the mutant's
index; each mutant is then a :class:`~openpbr_diffuse.graders.subject.Subject` whose calls
share one run over all mutants, graded with ``graders.grading.grade_subject`` exactly as
``check --glsl/--cpp`` grades one file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SUBJECTS = Path(__file__).resolve().parent / "subjects"
GLSL_FILE = SUBJECTS / "eon_conforming.glsl"
CPP_FILE = SUBJECTS / "eon_conforming.cpp"

_GLSL_TO_CPP = (
    (r"(?<![\w:.])(max|min|sqrt|acos|sin|cos)\(", r"std::\1("),
    (r"(?<![\w:.])(vec3|clamp|dot)\(", r"glm::\1("),
    (r"(?<![\w.])(\d+\.\d*(?:e[-+]?\d+)?|\d+e[-+]?\d+)(?![\w.])", r"\1f"),
)


def to_cpp(text: str) -> str:
    """A GLSL statement as the C++ subject writes it (std:: maths, glm:: types, float literals)."""
    for pattern, repl in _GLSL_TO_CPP:
        text = re.sub(pattern, repl, text)
    return text


@dataclass(frozen=True)
class Edit:
    """Replace ``old`` by ``new`` (exactly ``count`` times); ``cpp``: (old, new) for C++ if not to_cpp."""

    old: str
    new: str
    count: int = 1
    cpp: tuple | None = None

    def apply(self, text: str, language: str) -> str:
        old, new = (self.old, self.new) if language == "glsl" else (self.cpp or (to_cpp(self.old), to_cpp(self.new)))
        found = text.count(old)
        if found != self.count:
            raise AssertionError(f"{language} edit {old!r}: found {found} times, expected {self.count}")
        return text.replace(old, new)


@dataclass(frozen=True)
class Mutant:
    """A mutant: its edits, the diagnosis expected for BRDF and for the albedo (None: the albedo
    is unchanged and must conform; NOT_EXPLAINED: matches no known deviation), and a fragment
    the BRDF's diagnosis sentence must hold."""

    name: str
    edits: tuple
    brdf: str | None
    albedo: str | None
    fragment: str = ""


NOT_EXPLAINED = "<not explained>"

_F_RETURN = "return f_ss + f_ms;"
_E_RETURN = "return rho * EF + rho_ms * (1.0 - EF);"
_ROUGH = "float r = roughness;"
_F_MS = "f_ms = rho_ms / EON_PI"
_SRGB_GLSL = (
    "vec3 f(vec3 wi,",
    (
        "vec3 eon_srgb_encode(vec3 x)\n{\n"
        "    return mix(1.055 * pow(max(x, vec3(0.0)), vec3(1.0 / 2.4)) - 0.055, 12.92 * x,\n"
        "               lessThanEqual(x, vec3(0.0031308)));\n}\n\nvec3 f(vec3 wi,"
    ),
)
_SRGB_CPP = (
    "glm::vec3 f(glm::vec3 wi,",
    (
        "static glm::vec3 eon_srgb_encode(glm::vec3 x)\n{\n"
        "    for (int k = 0; k < 3; ++k)\n"
        "        x[k] = x[k] <= 0.0031308f ? 12.92f * x[k] : 1.055f * std::pow(x[k], 1.0f / 2.4f) - 0.055f;\n"
        "    return x;\n}\n\nglm::vec3 f(glm::vec3 wi,"
    ),
)
_QON_F = (
    "float A = 1.0 - 0.5 * r * r / (r * r + 0.33), B = 0.45 * r * r / (r * r + 0.09);\n"
    "    return rho / EON_PI * (A + B * max(0.0, s) / max(mu_i, mu_o));"
)
# QON's albedo (Oren-Nayar 1994 Eq. 5, 8): rho (A + B/pi G), G = S (theta - S mu) + (2/3) tan(theta) (1 - S^3)
_QON_E = (
    "float th = acos(mu), S = sqrt(max(0.0, 1.0 - mu * mu));\n"
    "    float A = 1.0 - 0.5 * r * r / (r * r + 0.33), B = 0.45 * r * r / (r * r + 0.09);\n"
    "    float G = S * (th - S * mu) + (2.0 / 3.0) * S * mu * (1.0 + S + S * S) / (1.0 + S);\n"
    "    return rho * (A + B / EON_PI * G);"
)
# the Eq. 14 fit of E_F put in front of the exact body (which is then never reached)
_EQ14 = (
    "float eon_EF(float mu, float r)\n{",
    (
        "float eon_EF(float mu, float r)\n{\n    float m = 1.0 - mu;\n"
        "    return (1.0 + r * m * (0.0571085289 + m * (0.491881867 + m * (-0.332181442 + m * 0.0714429953))))\n"
        "           / (1.0 + EON_C1 * r);"
    ),
)

MUTANTS = {
    m.name: m
    for m in (
        Mutant(
            "pi_forgotten",
            (Edit("rho / EON_PI * AF", "rho * AF"), Edit(_F_MS, "f_ms = rho_ms")),
            "constant_factor",
            None,
            "x 3.1416 (1/pi forgotten)",
        ),
        Mutant(
            "any_scale",
            (
                Edit(_F_RETURN, "return 0.731 * (f_ss + f_ms);"),
                Edit(_E_RETURN, "return 0.731 * (rho * EF + rho_ms * (1.0 - EF));"),
            ),
            "constant_factor",
            "constant_factor",
            "x 0.731",
        ),
        Mutant("ms_missing_inv_pi", (Edit(_F_MS, "f_ms = rho_ms"),), "ms_missing_inv_pi", None, "f_ms"),
        Mutant(
            "ms_extra_inv_pi",
            (
                Edit(_F_MS, "f_ms = rho_ms / EON_PI / EON_PI"),
                Edit("rho_ms * (1.0 - EF)", "rho_ms / EON_PI * (1.0 - EF)"),
            ),
            "rho_ms_extra_inv_pi",
            "rho_ms_extra_inv_pi",
            "f_ms",
        ),
        Mutant(
            "ms_extra_rho",
            (Edit(_F_MS, "f_ms = rho * rho_ms / EON_PI"), Edit("rho_ms * (1.0 - EF)", "rho * rho_ms * (1.0 - EF)")),
            "rho_ms_extra_rho",
            "rho_ms_extra_rho",
        ),
        Mutant("cos_included", (Edit(_F_RETURN, "return (f_ss + f_ms) * mu_i;"),), "times_cos_theta_i", None, "mu_i"),
        Mutant(
            "cos_divided_out",
            (Edit(_F_RETURN, "return (f_ss + f_ms) / mu_i;"),),
            "divided_by_cos_theta_i",
            None,
            "mu_i",
        ),
        Mutant(
            "cos_of_wo",
            (Edit(_F_RETURN, "return (f_ss + f_ms) * mu_o;"),),
            "times_cos_theta_i+wi_wo_swapped",
            None,
            "wi and wo swapped",
        ),
        Mutant(
            "sigma_vs_r",
            (Edit(_ROUGH, "float r = roughness * 2.0 / EON_PI;", 2),),
            "roughness_sigma_vs_r",
            "roughness_sigma_vs_r",
            "2r/pi",
        ),
        Mutant(
            "r_squared",
            (Edit(_ROUGH, "float r = roughness * roughness;", 2),),
            "roughness_squared",
            "roughness_squared",
            "r^2",
        ),
        Mutant(
            "degrees",
            (Edit(_ROUGH, "float r = roughness * (EON_PI / 180.0);", 2),),
            "roughness_degrees",
            "roughness_degrees",
            "pi/180",
        ),
        Mutant(
            "srgb_encoded",
            (Edit(*_SRGB_GLSL, cpp=_SRGB_CPP), Edit(_ROUGH, _ROUGH + "\n    rho = eon_srgb_encode(rho);", 2)),
            "rho_srgb_encoded",
            "rho_srgb_encoded",
            "srgb_encode",
        ),
        Mutant(
            "mu_floor",
            (
                Edit("float mu_i = wi.z, mu_o = wo.z;", "float mu_i = max(wi.z, 0.01), mu_o = max(wo.z, 0.01);"),
                Edit("float EF = eon_EF(mu, r);", "float EF = eon_EF(max(mu, 0.01), r);"),
            ),
            "mu_floor",
            "mu_floor",
            "max(mu, 0.01)",
        ),
        Mutant("eq14", (Edit(*_EQ14),), "eq14_fit_for_exact", "eq14_fit_for_exact", "--model eon_approx"),
        Mutant(
            "ldotv_clamped",
            (Edit("float LdotV = dot(wi, wo);", "float LdotV = clamp(dot(wi, wo), 1e-8, 1.0);"),),
            "ldotv_clamped",
            None,
        ),
        Mutant(
            "white_tint",
            (
                Edit(
                    _ROUGH,
                    _ROUGH + "\n    vec3 tint = rho; rho = vec3(1.0);",
                    2,
                    cpp=(_ROUGH, _ROUGH + "\n    glm::vec3 tint = rho; rho = glm::vec3(1.0f);"),
                ),
                Edit(_F_RETURN, "return tint * (f_ss + f_ms);"),
                Edit(_E_RETURN, "return tint * (rho * EF + rho_ms * (1.0 - EF));"),
            ),
            "white_tint",
            "white_tint",
        ),
        Mutant(
            "qon",
            (Edit(_F_RETURN, _QON_F), Edit(_E_RETURN, _QON_E)),
            "no_energy_compensation_qon",
            "no_energy_compensation_qon",
        ),
        Mutant(
            "fon",
            (Edit(_F_RETURN, "return f_ss;"), Edit(_E_RETURN, "return rho * EF;")),
            "no_energy_compensation_fon",
            "no_energy_compensation_fon",
        ),
        Mutant(
            "lambert",
            (Edit(_F_RETURN, "return rho / EON_PI;"), Edit(_E_RETURN, "return rho;")),
            "no_energy_compensation_lambert",
            "no_energy_compensation_lambert",
        ),
        # matches no known deviation: f x (1 + 0.3 sin(7 mu_i))
        Mutant(
            "sin_mu_i", (Edit(_F_RETURN, "return (f_ss + f_ms) * (1.0 + 0.3 * sin(7.0 * mu_i));"),), NOT_EXPLAINED, None
        ),
    )
}


def conforming(language: str) -> str:
    """The conforming subject's source ("glsl" or "cpp")."""
    return (GLSL_FILE if language == "glsl" else CPP_FILE).read_text()


def mutant_source(name: str, language: str) -> str:
    """The source of mutant ``name`` in ``language``, the conforming file with its edits applied."""
    text = conforming(language)
    for edit in MUTANTS[name].edits:
        text = edit.apply(text, language)
    if text == conforming(language):
        raise AssertionError(f"mutant {name} is the conforming source")
    return text


def write_mutant(name: str, language: str, folder: Path) -> Path:
    """Write mutant ``name`` to ``folder/<name>.glsl|cpp``."""
    path = Path(folder) / f"{name}.{language}"
    path.write_text(mutant_source(name, language))
    return path


_TOP_LEVEL = re.compile(r"\b(EON_\w+|eon_\w+|f|albedo)\b")


def _renamed(text: str, k: int) -> str:
    """Every top-level identifier of a subject suffixed with ``_m<k>`` (one copy per mutant)."""
    text = re.sub(r"^#include.*$", "", text, flags=re.MULTILINE)
    return _TOP_LEVEL.sub(lambda m: f"{m.group(1)}_m{k}", text)


def batch_subjects(names, language: str, folder: Path) -> dict:
    """{name: Subject} for the mutants ``names`` ("conforming" for the conforming code), run
    together: one GLSL shader or one C++ harness holding every copy, called once per kind
    (BRDF, albedo) over all mutants' rows."""
    from openpbr_diffuse.graders import cpp, glsl
    from openpbr_diffuse.graders._arrays import rows
    from openpbr_diffuse.graders.subject import Subject

    names = list(names)
    sources = [conforming(language) if n == "conforming" else mutant_source(n, language) for n in names]
    code = "\n".join(_renamed(s, k) for k, s in enumerate(sources))
    folder = Path(folder)
    if language == "glsl":

        def call(fn, args):
            return "\n    ".join(
                f"{'if' if k == 0 else 'else if'} (grader_k == {k}) grader_v = {fn}_m{k}({args});"
                for k in range(len(names))
            )

        k_brdf = glsl.Kernel(
            code=code,
            n_in=11,
            n_out=3,
            body=f"""
    int grader_k = int(IN(10) + 0.5);
    vec3 grader_v = vec3(0.0);
    {call("f", "vec3(IN(0), IN(1), IN(2)), vec3(IN(3), IN(4), IN(5)), IN(6), vec3(IN(7), IN(8), IN(9))")}
    OUT(0) = grader_v.x; OUT(1) = grader_v.y; OUT(2) = grader_v.z;""",
        )
        k_albedo = glsl.Kernel(
            code=code,
            n_in=6,
            n_out=3,
            body=f"""
    int grader_k = int(IN(5) + 0.5);
    vec3 grader_v = vec3(0.0);
    {call("albedo", "IN(0), IN(1), vec3(IN(2), IN(3), IN(4))")}
    OUT(0) = grader_v.x; OUT(1) = grader_v.y; OUT(2) = grader_v.z;""",
        )

        def run(kind, inputs):
            return (k_brdf if kind == "brdf" else k_albedo).run(inputs, f"{len(names)} {language} mutants")

        tolerance, reason = glsl.TOLERANCE, glsl.TOLERANCE_REASON
    else:
        path = folder / "mutants.hpp"
        path.write_text("#include <algorithm>\n#include <cmath>\n#include <glm/glm.hpp>\n" + code)

        def call(fn, args):
            cases = "\n    ".join(f"case {k}: grader_v = {fn}_m{k}({args}); break;" for k in range(len(names)))
            return f"glm::vec3 grader_v(0.0f);\n    switch (int(in[N] + 0.5f)) {{\n    {cases}\n    }}"

        harness = cpp.Harness(
            prelude=f'#include <glm/glm.hpp>\n#include "{path}"\n',
            entries={
                "brdf": cpp.Entry(
                    11,
                    3,
                    call(
                        "f",
                        "glm::vec3(in[0], in[1], in[2]), glm::vec3(in[3], in[4], in[5]), "
                        "in[6], glm::vec3(in[7], in[8], in[9])",
                    ).replace("in[N]", "in[10]")
                    + "\n    out[0] = grader_v[0]; out[1] = grader_v[1]; out[2] = grader_v[2];",
                ),
                "albedo": cpp.Entry(
                    6,
                    3,
                    call("albedo", "in[0], in[1], glm::vec3(in[2], in[3], in[4])").replace("in[N]", "in[5]")
                    + "\n    out[0] = grader_v[0]; out[1] = grader_v[1]; out[2] = grader_v[2];",
                ),
            },
            include_dirs=[str(folder)],
            sources=[path],
            label=f"{len(names)} C++ mutants",
        )

        def run(kind, inputs):
            return harness.run(kind, inputs)

        tolerance, reason = None, "compiled C++: the float32 tolerance of check FILE"

    cache = {}

    def shared(kind, k, args):
        key = (kind, *(np.asarray(a, np.float64).tobytes() for a in args))
        if key not in cache:
            one = rows(*args)
            every = np.concatenate([np.hstack([one, np.full((len(one), 1), j, np.float32)]) for j in range(len(names))])
            cache[key] = run(kind, every).reshape(len(names), len(one), 3)
        return cache[key][k]

    subjects = {}
    for k, name in enumerate(names):
        subjects[name] = Subject(
            name=f"{language}:{name}",
            model="eon",
            tolerance=tolerance,
            tolerance_reason=reason,
            brdf=lambda wi, wo, r, rho, k=k: shared("brdf", k, (wi, wo, r, rho)),
            albedo=lambda mu, r, rho, k=k: shared("albedo", k, (mu, r, rho)),
        )
    return subjects
