"""Generic adapters: grade any GLSL or C++ function with the documented signature.

GLSL (run on llvmpipe in a compute shader)::

    vec3 NAME(vec3 wi, vec3 wo, float roughness, vec3 rho)   // BRDF f, no cosine, local frame
    vec3 NAME(float mu, float roughness, vec3 rho)           // directional albedo E(mu)
    vec3 NAME(vec3 wo, vec2 u, float roughness)              // sampler: wi for u in [0, 1)^2
    float NAME(vec3 wo, vec3 wi, float roughness)            // its solid-angle pdf

C++ (compiled with g++ -std=c++17 against GLM)::

    glm::vec3 NAME(glm::vec3 wi, glm::vec3 wo, float roughness, glm::vec3 rho);
    glm::vec3 NAME(float mu, float roughness, glm::vec3 rho);
    glm::vec3 NAME(glm::vec3 wo, glm::vec2 u, float roughness);   // sampler
    float NAME(glm::vec3 wo, glm::vec3 wi, float roughness);      // its pdf

(any types constructible from those arguments and indexable with ``[0..2]`` work in C++).
The file is included unchanged; ``#include`` paths and preprocessor defines come from the
command line (``--include DIR``, ``--define NAME=VALUE``).  Directions point away from the
surface in the local frame whose normal is +z; ``mu`` is cos(theta_o).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

from . import cpp, glsl, limits
from ._arrays import rows
from .errors import GraderUnavailable
from .subject import Subject


def _check_file(path: str | os.PathLike[str], what: str) -> Path:
    path = Path(path)
    if not path.is_file():
        raise GraderUnavailable(f"{what} file {path} does not exist")
    return path


def _defines(defines):
    return limits.parse_defines(defines)


def _names(function, albedo_function, sample_function=None, pdf_function=None):
    for name, opt in (
        (function, "--function"),
        (albedo_function, "--albedo-function"),
        (sample_function, "--sample-function"),
        (pdf_function, "--pdf-function"),
    ):
        if name is not None:
            limits.check_identifier(name, opt)
    if (sample_function is None) != (pdf_function is None):
        raise ValueError("--sample-function and --pdf-function go together (the sampler is graded against its own pdf)")
    if not (function or albedo_function or sample_function):
        raise ValueError("--function, --albedo-function or --sample-function/--pdf-function is required")


def _glsl_functions(path, code_names, includes, defines):
    """The array functions (brdf, albedo, sample, pdf) of a GLSL file's named functions, and
    the defines they were built with."""
    function, albedo_function, sample_function, pdf_function = code_names
    code = glsl.resolve_includes(path, tuple(Path(i) for i in includes))
    defs = _defines(defines)
    kernel = functools.partial(glsl.Kernel, code=code, defines=defs)
    brdf = albedo = None
    label = str(path)
    if function:
        k_brdf = kernel(
            n_in=10,
            n_out=3,
            body=f"""
    vec3 grader_f = {function}(vec3(IN(0), IN(1), IN(2)), vec3(IN(3), IN(4), IN(5)), IN(6), vec3(IN(7), IN(8), IN(9)));
    OUT(0) = grader_f.x; OUT(1) = grader_f.y; OUT(2) = grader_f.z;""",
        )

        def brdf(wi, wo, roughness, rho):
            return k_brdf.run(rows(wi, wo, roughness, rho), label)

    if albedo_function:
        k_albedo = kernel(
            n_in=5,
            n_out=3,
            body=f"""
    vec3 grader_E = {albedo_function}(IN(0), IN(1), vec3(IN(2), IN(3), IN(4)));
    OUT(0) = grader_E.x; OUT(1) = grader_E.y; OUT(2) = grader_E.z;""",
        )

        def albedo(mu, roughness, rho):
            return k_albedo.run(rows(mu, roughness, rho), label)

    sample, pdf = (
        glsl.sampler_functions(code, sample_function, pdf_function, defs, label)
        if sample_function and pdf_function is not None  # given together (_names)
        else (None, None)
    )
    return (brdf, albedo, sample, pdf), defs


def _cpp_functions(path, code_names, includes, defines):
    """The array functions (brdf, albedo, sample, pdf) of a C++ file's named functions, and
    the defines they were compiled with."""
    function, albedo_function, sample_function, pdf_function = code_names
    entries = {}
    if function:
        entries["brdf"] = cpp.Entry(
            10,
            3,
            f"""
    const auto grader_f = {function}(glm::vec3(in[0], in[1], in[2]), glm::vec3(in[3], in[4], in[5]), in[6],
                              glm::vec3(in[7], in[8], in[9]));
    out[0] = grader_f[0]; out[1] = grader_f[1]; out[2] = grader_f[2];""",
        )
    if albedo_function:
        entries["albedo"] = cpp.Entry(
            5,
            3,
            f"""
    const auto grader_E = {albedo_function}(in[0], in[1], glm::vec3(in[2], in[3], in[4]));
    out[0] = grader_E[0]; out[1] = grader_E[1]; out[2] = grader_E[2];""",
        )
    if sample_function and pdf_function is not None:  # given together (_names)
        entries.update(cpp.sampler_entries(sample_function, pdf_function))
    prelude = f'#include <glm/glm.hpp>\n#include "{path.resolve()}"\n'
    h = cpp.Harness(
        prelude=prelude,
        entries=entries,
        include_dirs=[str(path.parent.resolve()), *map(str, includes)],
        defines=_defines(defines),
        sources=[path],
        label=str(path),
    )
    h.binary()
    brdf = albedo = None
    if function:

        def brdf(wi, wo, roughness, rho):
            return h.run("brdf", rows(wi, wo, roughness, rho))

    if albedo_function:

        def albedo(mu, roughness, rho):
            return h.run("albedo", rows(mu, roughness, rho))

    sample, pdf = cpp.sampler_functions(h) if sample_function else (None, None)
    return (brdf, albedo, sample, pdf), _defines(defines)


class _Language(NamedTuple):
    """How a source file of one language becomes a Subject."""

    what: str  # the language in messages
    functions: Callable[..., Any]  # (path, names, includes, defines) -> ((brdf, albedo, sample, pdf), defines)
    tolerance: tuple[float, float] | None  # (relative, absolute); None: check FILE's float32 one
    tolerance_reason: str
    tool: str  # the key of the tool's version in Subject.version
    tool_version: Callable[[], str]


_LANGUAGES = {
    "glsl": _Language("GLSL", _glsl_functions, glsl.TOLERANCE, glsl.TOLERANCE_REASON, "gl", glsl.gl_version),
    "cpp": _Language(
        "C++",
        _cpp_functions,
        None,
        "compiled C++: the float32 tolerance of check FILE",
        "compiler",
        cpp.compiler_version,
    ),
}


def _file_subject(kind, path, code_names, includes, defines, model):
    """The Subject of the functions ``code_names`` = (brdf, albedo, sample, pdf names) of the
    ``kind`` (``glsl``, ``cpp``) file ``path``."""
    language = _LANGUAGES[kind]
    path = _check_file(path, language.what)
    _names(*code_names)
    (brdf, albedo, sample, pdf), defs = language.functions(path, code_names, includes, defines)
    function, albedo_function, sample_function, _ = code_names
    return Subject(
        name=f"{kind}:{path.name}:{function or albedo_function or sample_function}",
        model=model,
        tolerance=language.tolerance,
        tolerance_reason=language.tolerance_reason,
        version={
            "source": str(path.resolve()),
            "sha256": glsl.sources_hash([path]),
            language.tool: language.tool_version(),
            "defines": defs,
        },
        brdf=brdf,
        albedo=albedo,
        sample=sample,
        pdf=pdf,
    )


def glsl_subject(
    path: str | os.PathLike[str],
    function: str | None = None,
    albedo_function: str | None = None,
    *,
    includes: Sequence[str | os.PathLike[str]] = (),
    defines: Iterable[str] | dict = (),
    model: str = "eon",
    sample_function: str | None = None,
    pdf_function: str | None = None,
) -> Subject:
    """A GLSL file's BRDF function ``function``, albedo function ``albedo_function`` and/or
    sampler ``sample_function`` with its pdf ``pdf_function`` (given together)."""
    names = (function, albedo_function, sample_function, pdf_function)
    return _file_subject("glsl", path, names, includes, defines, model)


def cpp_subject(
    path: str | os.PathLike[str],
    function: str | None = None,
    albedo_function: str | None = None,
    *,
    includes: Sequence[str | os.PathLike[str]] = (),
    defines: Iterable[str] | dict = (),
    model: str = "eon",
    sample_function: str | None = None,
    pdf_function: str | None = None,
) -> Subject:
    """A C++ file's BRDF function ``function``, albedo function ``albedo_function`` and/or
    sampler ``sample_function`` with its pdf ``pdf_function`` (given together)."""
    names = (function, albedo_function, sample_function, pdf_function)
    return _file_subject("cpp", path, names, includes, defines, model)
