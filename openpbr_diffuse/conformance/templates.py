"""Starting files for another implementation: GLSL, C++ and the CSV vector file.

The GLSL and C++ templates hold the documented signatures (local shading frame, normal +z,
``wi`` towards the light and ``wo`` towards the viewer, both pointing away from the surface;
the BRDF value without the cosine factor)::

    vec3  f(vec3 wi, vec3 wo, float roughness, vec3 rho)    // BRDF
    vec3  albedo(float mu, float roughness, vec3 rho)       // directional albedo E(mu)
    vec3  sample_wi(vec3 wo, vec2 u, float roughness)       // a sampled wi for u in [0, 1)^2
    float pdf(vec3 wo, vec3 wi, float roughness)            // its solid-angle density

(C++: the same with ``glm::vec3`` / ``glm::vec2``).  The bodies are a Lambertian
placeholder, clearly marked, so that a template compiles and runs end to end before it is
filled in.  The CSV template is the vector file with empty ``out_r, out_g, out_b``.

Examples
--------
>>> "vec3 f(vec3 wi, vec3 wo, float roughness, vec3 rho)" in template_text("glsl")
True
"""

from __future__ import annotations

from pathlib import Path

from .._outfile import check_output_file, output_file

KINDS = ("glsl", "cpp", "csv")


def _header(language: str, option: str) -> str:
    """The comment that opens a code template: the conventions, the ``check`` command grading it."""
    return f"""\
// openpbr-diffuse conformance template ({language}).
//
// Local shading frame: the normal is +z; wi (towards the light) and wo (towards the viewer)
// both point away from the surface.  f is the BRDF value WITHOUT the cosine factor.
// roughness: r in [0, 1] for FON/EON (sigma in radians for QON); rho: linear RGB albedo.
//
// Grade it (THIS_FILE: this file's path; one line, run from a shell):
//   openpbr-diffuse check --{option} THIS_FILE --function f --albedo-function albedo --sample-function sample_wi --pdf-function pdf
//
// >>> PLACEHOLDER: a Lambertian lobe, so that this file compiles and runs as it is. <<<
// >>> Replace the four bodies with your implementation.                             <<<
"""


_GLSL = (
    _header("GLSL", "glsl")
    + """
const float TEMPLATE_PI = 3.14159265358979323846;

vec3 f(vec3 wi, vec3 wo, float roughness, vec3 rho)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);   // single-sided
    return rho / TEMPLATE_PI;                           // PLACEHOLDER (Lambert)
}

vec3 albedo(float mu, float roughness, vec3 rho)
{
    return rho;                                         // PLACEHOLDER (Lambert: E = rho)
}

vec3 sample_wi(vec3 wo, vec2 u, float roughness)
{
    // PLACEHOLDER: cosine-weighted hemisphere sampling
    float r = sqrt(u.x);
    float phi = 2.0 * TEMPLATE_PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

float pdf(vec3 wo, vec3 wi, float roughness)
{
    return max(wi.z, 0.0) / TEMPLATE_PI;                // PLACEHOLDER (cosine sampling)
}
"""
)

_CPP = (
    _header("C++17, GLM", "cpp")
    + """\
#include <cmath>
#include <glm/glm.hpp>

static const float TEMPLATE_PI = 3.14159265358979323846f;

glm::vec3 f(glm::vec3 wi, glm::vec3 wo, float roughness, glm::vec3 rho)
{
    if (wi.z <= 0.0f || wo.z <= 0.0f) return glm::vec3(0.0f);   // single-sided
    return rho / TEMPLATE_PI;                                   // PLACEHOLDER (Lambert)
}

glm::vec3 albedo(float mu, float roughness, glm::vec3 rho)
{
    return rho;                                                 // PLACEHOLDER (Lambert: E = rho)
}

glm::vec3 sample_wi(glm::vec3 wo, glm::vec2 u, float roughness)
{
    // PLACEHOLDER: cosine-weighted hemisphere sampling
    const float r = std::sqrt(u.x);
    const float phi = 2.0f * TEMPLATE_PI * u.y;
    return glm::vec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::fmax(0.0f, 1.0f - u.x)));
}

float pdf(glm::vec3 wo, glm::vec3 wi, float roughness)
{
    return std::fmax(wi.z, 0.0f) / TEMPLATE_PI;                 // PLACEHOLDER (cosine sampling)
}
"""
)


def template_text(kind: str) -> str:
    """The text of the ``kind`` template ("glsl" or "cpp"; "csv": use :func:`write_template`)."""
    if kind == "glsl":
        return _GLSL
    if kind == "cpp":
        return _CPP
    raise ValueError(f"kind: expected 'glsl' or 'cpp' for a code template, got {kind!r}")


def write_template(kind: str, path: str | Path, *, force: bool = False) -> Path:
    """Write the ``kind`` template ("glsl", "cpp" or "csv") to ``path``.

    An existing file is never replaced unless ``force``, and then only a regular file (not
    a symbolic link): the rule of every output file,
    :func:`openpbr_diffuse._outfile.output_file` (a temporary sibling takes the name once
    complete).  The CSV (or JSON, when the name ends in ``.json``) template is the default
    vector set with empty result columns.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``force`` is false (``OutputExistsError``, also a ``ValueError``).
    ValueError
        ``path`` may not be written (a symbolic link, a folder, a missing folder, ...).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> write_template("glsl", d / "f.glsl").read_text() == template_text("glsl")
    True
    >>> write_template("glsl", d / "f.glsl")
    Traceback (most recent call last):
    ...
    openpbr_diffuse._outfile.OutputExistsError: --out .../f.glsl exists: not overwritten (use --force to replace it)
    """
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    path = Path(path)
    check_output_file(path, option="--out", force=force)  # before any work
    with output_file(path, option="--out", force=force) as tmp:
        if kind == "csv":
            from .vectors import default_vectors, write_vectors

            write_vectors(default_vectors(), tmp, blank_out=True)
        else:
            tmp.write_text(template_text(kind))
    return path


__all__ = ["KINDS", "template_text", "write_template"]
