"""The generic adapters (--glsl / --cpp) name each known deviation in a deliberately wrong function.

The functions below are written here, from the EON paper (Eq. 1-4, 10-13, 16-20), in GLSL and
in C++, with one preprocessor switch per known deviation; the adapters compile and run them
(llvmpipe / g++) on the conformance vectors and must fail each wrong one with that deviation's
name, and pass the right one.  Nothing here calls the library's models: the expected diagnosis
is the deviation that was written in.
"""

import json
import re

import pytest
from _system import requires

from openpbr_diffuse.cli.main import main

# switch -> the deviation name grade() must give; "albedo": True when the switch changes E(mu)
DEVIATIONS = {
    "DEV_QON": ("no_energy_compensation_qon", True),
    "DEV_FON": ("no_energy_compensation_fon", True),
    "DEV_INV_PI": ("rho_ms_extra_inv_pi", True),
    "DEV_EXTRA_RHO": ("rho_ms_extra_rho", True),
    "DEV_LDOTV": ("ldotv_clamped", False),
    "DEV_WHITE_TINT": ("white_tint", True),
    "DEV_COS": ("times_cos_theta_i", False),
    "DEV_SIGMA_VS_R": ("roughness_sigma_vs_r", True),
    "DEV_SQUARED": ("roughness_squared", True),
}

GLSL = r"""
const float PI_T = 3.14159265358979;
const float C1 = 0.5 - 2.0 / (3.0 * PI_T);
const float C2 = 2.0 / 3.0 - 28.0 / (15.0 * PI_T);

float rough(float r) {
#if defined(DEV_SIGMA_VS_R)
    return r * 2.0 / PI_T;
#elif defined(DEV_SQUARED)
    return r * r;
#else
    return r;
#endif
}

float E_F(float mu, float r) {            // Eq. 12-13, with the grazing limit E_F(0) = 1
    if (mu <= 0.0) return 1.0;
    float S = sqrt(max(0.0, 1.0 - mu * mu));
    float G = S * (acos(clamp(mu, -1.0, 1.0)) - S * mu) + (2.0 / 3.0) * ((S / mu) * (1.0 - S * S * S) - S);
    return (1.0 + r * G / PI_T) / (1.0 + C1 * r);
}

vec3 rho_ms(vec3 rho, float r) {          // Eq. 17
    float avg = (1.0 + C2 * r) / (1.0 + C1 * r);
    return rho * rho * avg / (vec3(1.0) - rho * (1.0 - avg));
}

vec3 f_test(vec3 wi, vec3 wo, float r, vec3 rho) {
    if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);
    r = rough(r);
#ifdef DEV_WHITE_TINT
    vec3 tint = rho; rho = vec3(1.0);
#endif
    float LdotV = dot(wi, wo);
#ifdef DEV_LDOTV
    LdotV = clamp(LdotV, 1e-8, 1.0);
#endif
    float s = LdotV - wi.z * wo.z;
#ifdef DEV_QON
    float s2 = r * r, A = 1.0 - 0.5 * s2 / (s2 + 0.33), B = 0.45 * s2 / (s2 + 0.09);
    vec3 f = rho / PI_T * (A + B * max(0.0, s) / max(wi.z, wo.z));
#else
    float st = s > 0.0 ? s / max(wi.z, wo.z) : s;
    vec3 f = rho / PI_T * (1.0 + r * st) / (1.0 + C1 * r);
#ifndef DEV_FON
    float avg = (1.0 + C2 * r) / (1.0 + C1 * r);
    vec3 fms = rho_ms(rho, r) / PI_T * (1.0 - E_F(wo.z, r)) * (1.0 - E_F(wi.z, r)) / max(1e-7, 1.0 - avg);
#ifdef DEV_INV_PI
    fms /= PI_T;
#endif
#ifdef DEV_EXTRA_RHO
    fms *= rho;
#endif
    f += fms;
#endif
#endif
#ifdef DEV_WHITE_TINT
    f *= tint;
#endif
#ifdef DEV_COS
    f *= wi.z;
#endif
    return f;
}

vec3 E_test(float mu, float r, vec3 rho) {
    r = rough(r);
#ifdef DEV_WHITE_TINT
    vec3 tint = rho; rho = vec3(1.0);
#endif
#ifdef DEV_QON
    float s2 = r * r, A = 1.0 - 0.5 * s2 / (s2 + 0.33), B = 0.45 * s2 / (s2 + 0.09);
    float G = PI_T / 2.0;                 // Eq. 8, G -> pi/2 at grazing
    if (mu > 0.0) {
        float th = acos(clamp(mu, -1.0, 1.0)), S = sqrt(max(0.0, 1.0 - mu * mu));
        G = S * (th - S * mu) + (2.0 / 3.0) * (S / mu) * (1.0 - S * S * S);
    }
    vec3 E = rho * (A + B / PI_T * G);
#else
    float EF = E_F(mu, r);
    vec3 E = rho * EF;
#ifndef DEV_FON
    vec3 ms = rho_ms(rho, r) * (1.0 - EF);
#ifdef DEV_INV_PI
    ms /= PI_T;
#endif
#ifdef DEV_EXTRA_RHO
    ms *= rho;
#endif
    E += ms;
#endif
#endif
#ifdef DEV_WHITE_TINT
    E *= tint;
#endif
    return E;
}
"""

# The same function in C++17 + GLM: the GLSL text with GLM names and float literals.
CPP = re.sub(
    r"(?<![\w.])(\d+\.\d*(?:e[-+]?\d+)?|\d+e[-+]?\d+)(?![\w.])",
    r"\1f",
    GLSL.replace("vec3", "glm::vec3")
    .replace("const float", "constexpr float")
    .replace("clamp(", "glm::clamp(")
    .replace("max(", "glm::max(")
    .replace("dot(", "glm::dot("),
)


def check(capsys, *args):
    status = main(["check", *args, "--json"])
    out = capsys.readouterr().out
    return status, (json.loads(out) if out.strip() else None)


def by_quantity(result):
    return {q["quantity"]: q for q in result["quantities"]}


needs_gl = requires("gl")
needs_cxx = requires("glm")


@pytest.fixture(scope="module")
def glsl_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("glsl") / "eon_test.glsl"
    path.write_text(GLSL)
    return path


@pytest.fixture(scope="module")
def cpp_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cpp") / "eon_test.hpp"
    path.write_text("#include <cmath>\n" + CPP)
    return path


@needs_gl
def test_glsl_adapter_passes_the_right_function(glsl_file, capsys):
    status, result = check(capsys, "--glsl", str(glsl_file), "--function", "f_test", "--albedo-function", "E_test")
    q = by_quantity(result)
    assert status == 0 and result["passed"], result
    assert q["brdf"]["n"] == 480 and q["albedo"]["n"] == 92  # the EON rows of the default vectors (v4)


@needs_gl
@pytest.mark.parametrize("switch", DEVIATIONS)
def test_glsl_adapter_names_the_deviation(glsl_file, capsys, switch):
    name, changes_albedo = DEVIATIONS[switch]
    status, result = check(
        capsys, "--glsl", str(glsl_file), "--function", "f_test", "--albedo-function", "E_test", "--define", switch
    )
    q = by_quantity(result)
    assert status == 1
    assert not q["brdf"]["passed"] and q["brdf"]["diagnosis"] == name, q["brdf"]["detail"]
    if changes_albedo:
        assert not q["albedo"]["passed"], q["albedo"]["detail"]
        # albedo rows alone may not tell two deviations apart (white tint and Lambert both give rho):
        # then the diagnosis names the other and says it cannot tell them apart
        detail = q["albedo"]["detail"]
        assert q["albedo"]["diagnosis"] == name or f"cannot tell it from: {name}" in detail, detail
    else:
        assert q["albedo"]["passed"]


@needs_cxx
def test_cpp_adapter_passes_the_right_function(cpp_file, capsys):
    status, result = check(capsys, "--cpp", str(cpp_file), "--function", "f_test", "--albedo-function", "E_test")
    assert status == 0 and result["passed"], result


@needs_cxx
@pytest.mark.parametrize("switch", ["DEV_EXTRA_RHO", "DEV_LDOTV"])
def test_cpp_adapter_names_the_deviation(cpp_file, capsys, switch):
    name, _ = DEVIATIONS[switch]
    status, result = check(capsys, "--cpp", str(cpp_file), "--function", "f_test", "--define", switch)
    q = by_quantity(result)
    assert status == 1 and q["brdf"]["diagnosis"] == name, q["brdf"]["detail"]


@needs_cxx
@pytest.mark.slow
@pytest.mark.parametrize("switch", DEVIATIONS)
def test_cpp_adapter_names_every_deviation(cpp_file, capsys, switch):
    name, changes_albedo = DEVIATIONS[switch]
    status, result = check(
        capsys, "--cpp", str(cpp_file), "--function", "f_test", "--albedo-function", "E_test", "--define", switch
    )
    q = by_quantity(result)
    assert status == 1 and q["brdf"]["diagnosis"] == name, q["brdf"]["detail"]
    if changes_albedo:
        detail = q["albedo"]["detail"]
        assert q["albedo"]["diagnosis"] == name or f"cannot tell it from: {name}" in detail, detail
    else:
        assert q["albedo"]["passed"]
