"""MaterialX's shipped GLSL for ``oren_nayar_diffuse_bsdf``, run on llvmpipe.

The subject is ``libraries/pbrlib/genglsl/mx_oren_nayar_diffuse_bsdf.glsl`` inside the
installed MaterialX package, with its includes resolved relative to each file, then against
``libraries/``, exactly as MaterialX's GLSL generator resolves them.  Library files are not
standalone: they expect the generator's prologue (``struct BSDF``, ``#define
DIRECTIONAL_ALBEDO_METHOD``, ``stdlib/genglsl/lib/mx_math.glsl``) and contain generator tokens
(``$closureDataConstructor``, ``$albedoTable``, ``$texSamplerSignature``, ...).  Both are taken
from a shader that MaterialX's own ``GlslShaderGenerator`` generates for an
``oren_nayar_diffuse_bsdf`` node, never typed here: each token's value is read off the generated
line that corresponds to the library line holding the token.

Conventions of the closure: with ``closureType == CLOSURE_TYPE_REFLECTION`` it returns
``response = f · N·L`` (a radiance response to unit irradiance along L, i.e. f·cos θ_i), so the
grader divides by N·L to get f; with ``CLOSURE_TYPE_INDIRECT`` it returns
``mx_environment_irradiance(N) · E(N·V)``, and the wrapper's environment is uniform white
(irradiance 1), so the response is the directional albedo.
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

from . import glsl
from ._arrays import rows
from .errors import GraderUnavailable
from .subject import Subject

NODE_FILE = "pbrlib/genglsl/mx_oren_nayar_diffuse_bsdf.glsl"
MATH_FILE = "stdlib/genglsl/lib/mx_math.glsl"
TOLERANCE, TOLERANCE_REASON = glsl.TOLERANCE, glsl.TOLERANCE_REASON
_TOKEN = re.compile(r"\$[A-Za-z_][A-Za-z0-9_]*")
# The closure context of the wrapper: a uniform white environment (irradiance 1 from every
# normal), so the CLOSURE_TYPE_INDIRECT response is the directional albedo itself.
ENVIRONMENT = "vec3 mx_environment_irradiance(vec3 N) { return vec3(1.0); }\n"


def _materialx():
    try:
        import MaterialX as mx
    except ImportError as exc:
        raise GraderUnavailable("MaterialX is not installed: pip install MaterialX") from exc
    return mx


def libraries_folder() -> Path:
    """``libraries/`` of the installed MaterialX package."""
    mx = _materialx()
    for folder in mx.getDefaultDataSearchPath().asString().split(mx.PATH_LIST_SEPARATOR):
        candidate = Path(folder) / "libraries"
        if (candidate / NODE_FILE).is_file():
            return candidate
    candidate = Path(mx.__file__).parent / "libraries"
    if (candidate / NODE_FILE).is_file():
        return candidate
    raise GraderUnavailable(f"the MaterialX package has no {NODE_FILE}: pip install MaterialX")


@lru_cache(maxsize=4)
def generated_pixel_shader(energy_compensation: bool = True) -> str:
    """Pixel-stage GLSL that MaterialX's generator writes for one oren_nayar_diffuse_bsdf node."""
    mx = _materialx()
    try:
        from MaterialX import PyMaterialXGenGlsl as mx_glsl
        from MaterialX import PyMaterialXGenShader as mx_gen
    except ImportError as exc:
        raise GraderUnavailable(
            "MaterialX's GLSL generator (PyMaterialXGenGlsl) is missing: pip install MaterialX"
        ) from exc
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    doc = mx.createDocument()
    doc.importLibrary(lib)
    bsdf = doc.addNode("oren_nayar_diffuse_bsdf", "diffuse", "BSDF")
    bsdf.setInputValue("energy_compensation", bool(energy_compensation))
    surface = doc.addNode("surface", "surface", "surfaceshader")
    surface.setConnectedNode("bsdf", bsdf)
    generator = mx_glsl.GlslShaderGenerator.create()
    context = mx_gen.GenContext(generator)
    context.registerSourceCodeSearchPath(mx.getDefaultDataSearchPath())
    shader = generator.generate("grader", surface, context)
    return shader.getSourceCode(mx_gen.PIXEL_STAGE)


def token_values(library_text: str, generated: str, context: int = 3) -> dict[str, str]:
    """Value of each ``$token`` of ``library_text``, read off the generated shader.

    For every library line holding tokens, the generated shader is searched for the same
    ``context`` preceding non-blank lines followed by a line with the same text around the
    tokens (the generator substitutes tokens in place, line by line); the text it has where the
    library has the token is the token's value.

    >>> token_values("a\\nb\\nreturn $x;", "a\\nreturn y;\\na\\nb\\nreturn Data(1, 2);")
    {'$x': 'Data(1, 2)'}
    """
    values: dict[str, str] = {}
    gen = [line.strip() for line in generated.splitlines() if line.strip()]
    lib = [line.strip() for line in library_text.splitlines() if line.strip()]
    for i, line in enumerate(lib):
        tokens = _TOKEN.findall(line)
        if not tokens or line.startswith("//"):
            continue
        before = lib[max(0, i - context) : i]
        pattern = re.compile("^" + "(.+?)".join(re.escape(p) for p in _TOKEN.split(line)) + "$")
        for j in range(len(before), len(gen)):
            if gen[j - len(before) : j] != before:
                continue
            m = pattern.match(gen[j])
            if m:
                for token, value in zip(tokens, m.groups()):
                    if values.setdefault(token, value) != value:
                        raise GraderUnavailable(
                            f"MaterialX generator token {token} has two values ({values[token]!r}, {value!r})"
                        )
                break
    return values


def substitute_tokens(text: str, values: dict[str, str]) -> str:
    missing = sorted(set(_TOKEN.findall(text)) - set(values))
    # Lines with tokens the generated shader never used are functions that the node does not
    # call (e.g. the shadow-map helpers): such a token is left to fail the compile if used.
    if missing:
        raise GraderUnavailable("MaterialX generator tokens not found in the generated shader: " + ", ".join(missing))
    return _TOKEN.sub(lambda m: values[m.group(0)], text)


def prologue(generated: str) -> str:
    """The generator's declarations the library files assume: BSDF/EDF types, method defines,
    and the uniform samplers the substituted tokens name."""
    keep = []
    for line in generated.splitlines():
        s = line.strip()
        if (
            s.startswith("struct BSDF")
            or s.startswith("#define EDF")
            or s.startswith("#define DIRECTIONAL_ALBEDO_METHOD")
            or (s.startswith("uniform sampler2D u_albedoTable"))
        ):
            keep.append(s)
    return "\n".join(keep) + "\n"


def wrapped_source(libraries: Path) -> tuple[str, list[Path]]:
    """(GLSL text, files it came from): mx_math + the node file with includes and tokens resolved."""
    node = libraries / NODE_FILE
    math = libraries / MATH_FILE
    for f in (node, math):
        if not f.is_file():
            raise GraderUnavailable(f"{f} is missing: reinstall MaterialX (pip install MaterialX)")
    generated = generated_pixel_shader(True)
    seen: set = set()
    text = (
        glsl.resolve_includes(math, (libraries,), seen)
        + "\n"
        + ENVIRONMENT
        + glsl.resolve_includes(node, (libraries,), seen)
    )
    values = token_values(text, generated)
    files = sorted(seen, key=str)
    return prologue(generated) + substitute_tokens(text, values), files


def _closure_kernel(
    code: str, n_in: int, n_out: int, frame: str, closure: str, rho_roughness: str, ec: str, more: str = ""
) -> glsl.Kernel:
    """A fragment kernel that calls ``mx_oren_nayar_diffuse_bsdf`` once per row: ``frame`` sets
    V and N (and L) from the row, ``closure`` is the closure type and its light direction,
    ``rho_roughness`` the colour and roughness arguments; OUT(0..2) is the response, then ``more``."""
    return glsl.Kernel(
        code=code,
        n_in=n_in,
        n_out=n_out,
        stage="fragment",
        body=f"""
    {frame}
    ClosureData cd = makeClosureData({closure}, V, N, vec3(0.0), 1.0);
    BSDF bsdf = BSDF(vec3(0.0), vec3(1.0));
    mx_oren_nayar_diffuse_bsdf(cd, 1.0, {rho_roughness}, N, {ec}, bsdf);
    OUT(0) = bsdf.response.x; OUT(1) = bsdf.response.y; OUT(2) = bsdf.response.z;{more}""",
    )


def subject(source: Path | None = None, energy_compensation: bool = True) -> Subject:
    """MaterialX's GLSL closure ``mx_oren_nayar_diffuse_bsdf`` (EON when energy_compensation)."""
    mx = _materialx()
    libraries = Path(source) if source is not None else libraries_folder()
    if source is not None and not (libraries / NODE_FILE).is_file():
        if (libraries / "libraries" / NODE_FILE).is_file():
            libraries = libraries / "libraries"
        else:
            raise GraderUnavailable(
                f"{source} does not hold MaterialX's {NODE_FILE}: pass --source "
                "MATERIALX/libraries, or omit --source to use the installed package"
            )
    code, files = wrapped_source(libraries)
    ec = "true" if energy_compensation else "false"
    # N = +z, the closure's local frame; P is unused by the node; occlusion 1.
    k_brdf = _closure_kernel(
        code,
        10,
        4,
        "vec3 L = vec3(IN(0), IN(1), IN(2)); vec3 V = vec3(IN(3), IN(4), IN(5)); vec3 N = vec3(0.0, 0.0, 1.0);",
        "CLOSURE_TYPE_REFLECTION, L",
        "vec3(IN(7), IN(8), IN(9)), IN(6)",
        ec,
        "\n    OUT(3) = clamp(dot(N, L), M_FLOAT_EPS, 1.0);",
    )
    k_albedo = _closure_kernel(
        code,
        5,
        3,
        "float mu = IN(0); vec3 V = vec3(sqrt(max(0.0, 1.0 - mu*mu)), 0.0, mu); vec3 N = vec3(0.0, 0.0, 1.0);",
        "CLOSURE_TYPE_INDIRECT, vec3(0.0)",
        "vec3(IN(2), IN(3), IN(4)), IN(1)",
        ec,
    )
    label = f"MaterialX {mx.getVersionString()} {NODE_FILE}"

    def brdf(wi, wo, roughness, rho):
        out = k_brdf.run(rows(wi, wo, roughness, rho), label)
        # response = f * N.L with MaterialX's own clamp of N.L: divide by the same N.L to get f;
        # directions below the horizon give f = 0 in the reference (the closure clamps instead).
        f = out[:, :3] / out[:, 3:4]
        below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
        f[below] = out[below, :3]
        return f

    def albedo(mu, roughness, rho):
        return k_albedo.run(rows(mu, roughness, rho), label)

    return Subject(
        name="materialx-glsl" if energy_compensation else "materialx-glsl-qon",
        model="eon" if energy_compensation else "qon",
        tolerance=TOLERANCE,
        tolerance_reason=TOLERANCE_REASON,
        version={
            "materialx": mx.getVersionString(),
            "source": str(libraries.resolve()),
            "files": [
                str(f.relative_to(libraries.resolve())) if f.is_relative_to(libraries.resolve()) else str(f)
                for f in files
            ],
            "sha256": glsl.sources_hash(files),
            "gl": glsl.gl_version(),
        },
        brdf=brdf,
        albedo=albedo,
        notes=[
            "closure response (f·N·L, CLOSURE_TYPE_REFLECTION) divided by MaterialX's clamped N·L",
            "albedo: CLOSURE_TYPE_INDIRECT response under a uniform white environment (mx_environment_irradiance = 1)",
            f"energy_compensation = {ec}",
        ],
    )
