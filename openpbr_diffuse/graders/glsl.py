"""Run GLSL functions on the CPU: Mesa's llvmpipe through a headless moderngl EGL context.

A test subject's own GLSL source is wrapped, unchanged, in a compute shader (GLSL 4.30) that
reads one row of inputs per invocation from a storage buffer, calls the subject's function and
writes the result to a second buffer.  ``#include "file"`` lines are resolved relative to the
including file, then against the given search folders (MaterialX's ``libraries/``).

llvmpipe evaluates ``acos`` and friends with polynomial approximations (max abs error about
1.6e-4 on acos), so values computed in GLSL carry that error on top of float32 rounding.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import limits
from ._gpu_child import CHILD, FRAGMENT_WIDTH, LOCAL_SIZE, NO_COMPILE, NO_DEVICE, create_context
from .errors import GraderUnavailable

#: (relative, absolute) tolerance for values computed in GLSL on llvmpipe.  acos's absolute
#: error (<= 1.6e-4, measured over [-1, 1]) enters E_F through G_F scaled by B_F/pi <= 0.25,
#: i.e. <= 4e-5 on E_F, and f_ms through (1 - E_F) / (1 - <E_F>): <= ~5e-5 on f.  On the default
#: vectors the listings need only 5.4e-7 absolute on top of 1e-4 relative; 5e-5 covers the bound
#: and stays 400x below the smallest known deviation (2 %, extra rho on f_ms).
TOLERANCE = (1e-4, 5e-5)
TOLERANCE_REASON = (
    "GLSL on llvmpipe: float32 arithmetic (1e-4 relative, as check FILE) plus llvmpipe's "
    "acos approximation (<= 1.6e-4 in the angle, <= ~5e-5 on f through E_F): 5e-5 absolute"
)
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$', re.MULTILINE)
_CONTEXT = None


def gl_context() -> Any:
    """The process's standalone moderngl context (EGL, OpenGL >= 4.3), created once."""
    global _CONTEXT
    if _CONTEXT is None:
        try:
            _CONTEXT = create_context()
        except RuntimeError as exc:
            raise GraderUnavailable(str(exc)) from exc
    return _CONTEXT


_VERSION: str | None = None


def _gl_worker() -> limits.Worker:
    """The process's GL child (``_gpu_child gl``), which runs every GLSL job."""
    return limits.worker(limits.script_command(CHILD, "gl"))


def _no_device(reason: str) -> str:
    """The GL child's reason for having no context, plus the caller's memory limit when it is
    the lower one (EGL then fails to initialise as if no driver were installed)."""
    limit = limits.memory_in_force()
    if limit < limits.MEMORY:
        return (
            f"{reason}; or the memory limit in force (ulimit -v {limit // 1024} KiB) is too low for "
            f"Mesa's llvmpipe: {limits.raise_hint(limit, limits.MEMORY)}"
        )
    return reason


def gl_version() -> str:
    """``GL_RENDERER / GL_VERSION`` of the context the GLSL runs on, as the GL child reports it
    (the process makes no GL context of its own for it); GraderUnavailable without one."""
    global _VERSION
    if _VERSION is None:
        run = _gl_worker().request(pickle.dumps({"info": True}), label="reading the GL version")
        err = run.stderr.decode(errors="replace").strip()
        if run.returncode != 0:
            if run.returncode != NO_DEVICE and (limits.memory_message(err) or run.returncode < 0):
                raise GraderUnavailable(limits.memory_failure("the GL child", "Mesa's llvmpipe", run.returncode))
            last = err.splitlines()[-1] if err else f"status {run.returncode}"
            raise GraderUnavailable(_no_device(last) if run.returncode == NO_DEVICE else f"the GL child failed: {last}")
        _VERSION = run.stdout.decode()
    return _VERSION


def resolve_includes(path: Path, search: tuple[Path, ...] = (), _seen: set | None = None) -> str:
    """Return the text of ``path`` with its ``#include "…"`` lines replaced by the files.

    Each file is included once (MaterialX's library files rely on that, like include guards).
    """
    path = Path(path)
    seen = set() if _seen is None else _seen
    key = path.resolve()
    if key in seen:
        return ""
    seen.add(key)
    text = path.read_text()

    def sub(match):
        name = match.group(1)
        for folder in (path.parent, *search):
            candidate = Path(folder) / name
            if candidate.is_file():
                return resolve_includes(candidate, search, seen)
        raise GraderUnavailable(
            f'{path}: #include "{name}" not found next to the file or in '
            f'{", ".join(str(s) for s in search) or "no search path"} (pass --include DIR)'
        )

    return _INCLUDE.sub(sub, text)


def sources_hash(paths: Iterable[str | os.PathLike[str]]) -> str:
    """SHA-256 over the given files' bytes, in the given order (the version of a source tree)."""
    h = hashlib.sha256()
    for p in paths:
        h.update(Path(p).name.encode())
        h.update(Path(p).read_bytes())
    return h.hexdigest()


@dataclass
class Kernel:
    """A compute shader around a subject's code: ``n_in`` floats in, ``n_out`` floats out per row.

    ``code`` is the subject's source (includes resolved), ``body`` the GLSL statements of the
    per-row call: they read ``float x[n_in]`` (``IN(k)``) and assign ``OUT(k)``.
    """

    code: str
    body: str
    n_in: int
    n_out: int
    preamble: str = ""
    defines: dict = field(default_factory=dict)
    uniforms: dict = field(default_factory=dict)
    stage: str = "compute"
    _program: object = field(default=None, repr=False, compare=False)

    def source(self) -> str:
        """The shader text: ``compute``, or ``fragment`` for code that uses fragment-only
        built-ins (``fwidth`` in MaterialX's mx_math.glsl); both read and write the same
        storage buffers, one row per invocation / fragment."""
        defines = "".join(f"#define {k} {v}\n" for k, v in self.defines.items())
        if self.stage == "compute":
            head = f"#version 430\nlayout(local_size_x={LOCAL_SIZE}) in;\n"
            row = "gl_GlobalInvocationID.x"
        else:
            head = "#version 430\nout vec4 grader_colour;\n"
            row = f"uint(gl_FragCoord.y) * {FRAGMENT_WIDTH}u + uint(gl_FragCoord.x)"
        return (
            head + f"{defines}{self.preamble}\n"
            "#line 1 1\n"
            f"{self.code}\n"
            "#line 1 2\n"
            "layout(std430, binding=0) readonly buffer GraderIn { float grader_in[]; };\n"
            "layout(std430, binding=1) writeonly buffer GraderOut { float grader_out[]; };\n"
            "uniform int grader_rows;\n"
            f"#define IN(k) grader_in[grader_row * {self.n_in}u + uint(k)]\n"
            f"#define OUT(k) grader_out[grader_row * {self.n_out}u + uint(k)]\n"
            "void main() {\n"
            f"    uint grader_row = {row};\n"
            "    if (grader_row >= uint(grader_rows)) return;\n"
            f"{self.body}\n"
            "}\n"
        )

    def run(self, inputs: np.ndarray, label: str = "shader") -> np.ndarray:
        """Run on ``inputs`` (rows, n_in) and return (rows, n_out) float32 results.

        The shader is compiled and run in a child process (``_gpu_child``, the process's GL
        worker: one child for every run, its GL context made once) under the limits of user
        code (:mod:`.limits`): a shader that never ends is killed with every process of the run.
        """
        inputs = np.ascontiguousarray(inputs, dtype=np.float32).reshape(-1, self.n_in)
        rows = inputs.shape[0]
        if rows == 0:
            return np.zeros((0, self.n_out), np.float32)
        job = {
            "source": self.source(),
            "stage": self.stage,
            "n_out": self.n_out,
            "rows": rows,
            "uniforms": dict(self.uniforms),
            "inputs": inputs.tobytes(),
        }
        run = _gl_worker().request(pickle.dumps(job), label=f"{label} (GLSL on llvmpipe)")
        err = run.stderr.decode(errors="replace").strip()
        if run.returncode == NO_DEVICE:
            raise GraderUnavailable(_no_device(err.splitlines()[-1] if err else "no OpenGL 4.3 context through EGL"))
        if run.returncode == NO_COMPILE:
            raise GraderUnavailable(
                f"{label} does not compile on {gl_version()}: {err.splitlines()[-1] if err else ''} "
                "(file 1 = the subject's code, 2 = the grader's wrapper)"
            )
        if run.returncode != 0:
            if limits.memory_message(err) or run.returncode < 0:
                raise GraderUnavailable(
                    limits.memory_failure(f"{label}: the GL child", "Mesa's llvmpipe", run.returncode)
                )
            last = err.splitlines()[-1] if err else f"status {run.returncode}"
            raise GraderUnavailable(f"{label}: the GL child failed: {last}")
        out = np.frombuffer(run.stdout, dtype=np.float32)
        if out.size != rows * self.n_out:
            raise GraderUnavailable(f"{label}: the GL child wrote {out.size} values, expected {rows * self.n_out}")
        return out.reshape(rows, self.n_out).copy()


def sampler_functions(
    code: str, sample_function: str, pdf_function: str, defines: dict | None = None, label: str = "shader"
) -> tuple[Callable[..., Any], Callable[..., Any]]:
    """``(sample, pdf)`` array functions around a subject's GLSL sampler and pdf.

    The GLSL signatures (local frame, normal +z, directions pointing away from the surface)::

        vec3  SAMPLE(vec3 wo, vec2 u, float roughness)   // a sampled wi for u in [0, 1)^2
        float PDF(vec3 wo, vec3 wi, float roughness)     // its solid-angle density

    ``sample(wo (n,3), roughness (n,), u (n,2)) -> (wi (n,3), pdf (n,))`` runs both in one
    shader invocation per row (``pdf`` is PDF at the returned wi, as a renderer would call it);
    ``pdf(wo, wi, roughness) -> (n,)`` runs PDF alone.  Each call is one run of the GL child
    (about 1 s on llvmpipe whatever the row count), so callers batch their rows;
    ``sample.combined(wo_s, roughness_s, u, wo_p, wi_p, roughness_p) -> (wi, pdf at wi, pdf)``
    runs both batches in one shader run (what ``graders.grading.grade_sampler`` uses).

    Examples
    --------
    >>> s, p = sampler_functions("vec3 S(vec3 wo, vec2 u, float r) { return vec3(0, 0, 1); }"
    ...                          "float P(vec3 wo, vec3 wi, float r) { return 1.0; }", "S", "P")
    >>> callable(s) and callable(p)       # nothing runs until called
    True
    """
    from ._arrays import rows

    defs = dict(defines or {})

    def kernel(n_in: int, n_out: int, body: str) -> Kernel:
        return Kernel(code=code, n_in=n_in, n_out=n_out, defines=defs, body=body)

    k_sample = kernel(
        6,
        4,
        f"""
    vec3 grader_wo = vec3(IN(0), IN(1), IN(2));
    float grader_r = IN(5);
    vec3 grader_wi = {sample_function}(grader_wo, vec2(IN(3), IN(4)), grader_r);
    float grader_p = {pdf_function}(grader_wo, grader_wi, grader_r);
    OUT(0) = grader_wi.x; OUT(1) = grader_wi.y; OUT(2) = grader_wi.z; OUT(3) = grader_p;""",
    )
    k_pdf = kernel(
        7,
        1,
        f"""
    OUT(0) = {pdf_function}(vec3(IN(0), IN(1), IN(2)), vec3(IN(3), IN(4), IN(5)), IN(6));""",
    )
    # both in one run: IN(0) = 1 for a sample row (wo, u, -, r), 0 for a pdf row (wo, wi, r)
    k_both = kernel(
        8,
        4,
        f"""
    vec3 grader_wo = vec3(IN(1), IN(2), IN(3));
    float grader_r = IN(7);
    if (IN(0) > 0.5) {{
        vec3 grader_wi = {sample_function}(grader_wo, vec2(IN(4), IN(5)), grader_r);
        OUT(0) = grader_wi.x; OUT(1) = grader_wi.y; OUT(2) = grader_wi.z;
        OUT(3) = {pdf_function}(grader_wo, grader_wi, grader_r);
    }} else {{
        OUT(0) = 0.0; OUT(1) = 0.0; OUT(2) = 0.0;
        OUT(3) = {pdf_function}(grader_wo, vec3(IN(4), IN(5), IN(6)), grader_r);
    }}""",
    )

    def sample(wo, roughness, u):
        out = k_sample.run(rows(wo, u, roughness), f"{label} ({sample_function})")
        return out[:, :3], out[:, 3]

    def pdf(wo, wi, roughness):
        return k_pdf.run(rows(wo, wi, roughness), f"{label} ({pdf_function})")[:, 0]

    def combined(wo_s, roughness_s, u, wo_p, wi_p, roughness_p):
        n_s = np.asarray(u).shape[0]
        a = rows(1.0, wo_s, u, 0.0, roughness_s, n=n_s)
        b = rows(0.0, wo_p, wi_p, roughness_p, n=np.asarray(wi_p).shape[0])
        out = k_both.run(np.concatenate([a, b]), f"{label} ({sample_function}, {pdf_function})")
        return out[:n_s, :3], out[:n_s, 3], out[n_s:, 3]

    sample.combined = combined  # type: ignore[attr-defined]  # one GL pass for both, when the grader can
    return sample, pdf
