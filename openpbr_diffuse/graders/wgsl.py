"""Run a user's WGSL functions through wgpu (Mesa's lavapipe without a GPU): ``check --wgsl``.

The file's text is wrapped, unchanged, in a compute shader that reads one row of inputs per
invocation from a storage buffer, calls the function and writes the result to a second one;
the shader runs in the graders' WGSL child (:mod:`._gpu_child`, as the Babylon.js grader's WGSL
paths do) under the limits of user code.  The signatures (local frame, normal +z, directions
pointing away from the surface, f without the cosine)::

    fn NAME(wi: vec3<f32>, wo: vec3<f32>, roughness: f32, rho: vec3<f32>) -> vec3<f32>   // --function
    fn NAME(mu: f32, roughness: f32, rho: vec3<f32>) -> vec3<f32>                        // --albedo-function
"""

from __future__ import annotations

import os
from pathlib import Path

from . import limits
from ._arrays import rows
from ._gpu_child import WORKGROUP
from .errors import GraderUnavailable
from .subject import Subject

#: (relative, absolute) tolerance: float32 on lavapipe, whose acos is the llvmpipe one the GLSL
#: grader's tolerance is made for (Mesa's gallivm), hence the same bound (graders.glsl.TOLERANCE)
TOLERANCE = (1e-4, 5e-5)
TOLERANCE_REASON = (
    "WGSL on lavapipe: float32 arithmetic (1e-4 relative) plus Mesa's acos approximation "
    "(<= 1.6e-4 in the angle, <= ~5e-5 on f through E_F): 5e-5 absolute, as --glsl"
)
_HARNESS = """
@group(0) @binding(0) var<storage, read> grader_in: array<f32>;
@group(0) @binding(1) var<storage, read_write> grader_out: array<f32>;
fn grader_v(k: u32) -> vec3<f32> {{ return vec3<f32>(grader_in[k], grader_in[k + 1u], grader_in[k + 2u]); }}
@compute @workgroup_size({workgroup}) fn main(@builtin(global_invocation_id) grader_gid: vec3<u32>) {{
    let k = grader_gid.x * {n_in}u;
    let grader_r: vec3<f32> = {call};
    let o = grader_gid.x * 3u;
    grader_out[o] = grader_r.x; grader_out[o + 1u] = grader_r.y; grader_out[o + 2u] = grader_r.z;
}}
"""


def harness(code: str, function: str, albedo: bool = False) -> str:
    """The compute shader around ``code`` calling ``function`` (the BRDF, or the albedo).

    Examples
    --------
    >>> src = harness("fn f(wi: vec3<f32>, wo: vec3<f32>, r: f32, rho: vec3<f32>) -> vec3<f32> { return rho; }", "f")
    >>> "f(grader_v(k), grader_v(k + 3u), grader_in[k + 6u], grader_v(k + 7u))" in src
    True
    """
    if albedo:
        call, n_in = f"{function}(grader_in[k], grader_in[k + 1u], grader_v(k + 2u))", 5
    else:
        call, n_in = f"{function}(grader_v(k), grader_v(k + 3u), grader_in[k + 6u], grader_v(k + 7u))", 10
    return code + "\n" + _HARNESS.format(workgroup=WORKGROUP, n_in=n_in, call=call)


def _version() -> str:
    from importlib import metadata

    try:
        return f"wgpu {metadata.version('wgpu')}"
    except metadata.PackageNotFoundError:
        return "wgpu not installed"


def wgsl_subject(
    path: str | os.PathLike[str],
    function: str | None = None,
    albedo_function: str | None = None,
    *,
    model: str = "eon",
) -> Subject:
    """A WGSL file's BRDF function ``function`` and/or albedo function ``albedo_function``.

    Nothing runs until a callable is called (each call is one run of the WGSL child).

    Raises
    ------
    ValueError
        A name is not an identifier, or neither is given.
    GraderUnavailable
        The file cannot be read (an ``OSError``).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "mine.wgsl"
    >>> _ = p.write_text("fn f(wi: vec3<f32>, wo: vec3<f32>, r: f32, rho: vec3<f32>) -> vec3<f32> { return rho; }")
    >>> s = wgsl_subject(p, "f")
    >>> s.name, s.brdf is not None, s.albedo is None
    ('wgsl:mine.wgsl:f', True, True)
    """
    from .babylon import _run_wgsl
    from .glsl import sources_hash

    if not (function or albedo_function):
        raise ValueError("--function or --albedo-function is required with --wgsl")
    for name, opt in ((function, "--function"), (albedo_function, "--albedo-function")):
        if name is not None:
            limits.check_identifier(name, opt)
    path = Path(path)
    try:
        code = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise GraderUnavailable(f"--wgsl {path}: cannot be read ({exc})") from None
    label = str(path)
    brdf = albedo = None
    if function:
        brdf_source = harness(code, function)

        def brdf(wi, wo, roughness, rho):
            return _run_wgsl(brdf_source, rows(wi, wo, roughness, rho), 3, label)

    if albedo_function:
        albedo_source = harness(code, albedo_function, albedo=True)

        def albedo(mu, roughness, rho):
            return _run_wgsl(albedo_source, rows(mu, roughness, rho), 3, label)

    return Subject(
        name=f"wgsl:{path.name}:{function or albedo_function}",
        model=model,
        tolerance=TOLERANCE,
        tolerance_reason=TOLERANCE_REASON,
        version={"source": str(path.resolve()), "sha256": sources_hash([path]), "wgpu": _version()},
        brdf=brdf,
        albedo=albedo,
    )


__all__ = ["TOLERANCE", "TOLERANCE_REASON", "harness", "wgsl_subject"]
