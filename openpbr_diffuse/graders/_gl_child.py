"""Child process that runs one GLSL kernel on llvmpipe (started by glsl.Kernel.run under limits).

Reads a pickled job (shader text, stage, row sizes, uniforms, inputs) on stdin from its parent
and writes the float32 outputs on stdout; a shader that does not compile exits with status 3
and one line on stderr, a machine without an OpenGL 4.3 context through EGL with status 4 and
the reason.  Running the GL part here lets the parent kill a shader that never ends.

The parent runs this file as a script (``CHILD``), not as a module of the package: it imports
numpy and moderngl only, so that a run does not import the package and numba (0.4 s of each
run's 0.55 s CPU, measured 2026-12-05).  The GL set-up the parent shares (the context, the row
layout of a fragment stage) is defined here and imported by :mod:`.glsl`.
"""

from __future__ import annotations

import pickle
import sys
from pathlib import Path
from typing import Any

#: this file, which the parent runs as a script
CHILD = Path(__file__).resolve()
#: compute shader work-group size (rows per group)
LOCAL_SIZE = 64
#: width of the fragment stage's target: row = y * FRAGMENT_WIDTH + x
FRAGMENT_WIDTH = 256
VERTEX = """#version 430
in vec2 grader_xy;
void main() { gl_Position = vec4(grader_xy, 0.0, 1.0); }
"""
#: what to install when there is no OpenGL 4.3 context through EGL
NO_CONTEXT = "install Mesa's software driver, e.g. apt-get install libgl1-mesa-dri libegl1 libegl-mesa0"


def create_context() -> Any:
    """A standalone moderngl context (EGL, OpenGL >= 4.3); RuntimeError naming what is missing."""
    try:
        import moderngl
    except ImportError as exc:
        raise RuntimeError("moderngl is not installed: pip install moderngl") from exc
    try:
        return moderngl.create_standalone_context(backend="egl", require=430)  # type: ignore[arg-type]  # the stub types every setting as a dict
    except Exception as exc:  # moderngl raises plain Exception for a missing driver
        raise RuntimeError(f"no OpenGL 4.3 context through EGL ({str(exc).splitlines()[0]}): {NO_CONTEXT}") from exc


def draw_rows(ctx: Any, program: Any, rows: int) -> None:
    """One fragment per row: a full-screen quad over a FRAGMENT_WIDTH x ceil(rows/width) target."""
    import numpy as np

    height = (rows + FRAGMENT_WIDTH - 1) // FRAGMENT_WIDTH
    target = ctx.renderbuffer((FRAGMENT_WIDTH, height), components=4, dtype="f1")
    fbo = ctx.framebuffer(color_attachments=[target])
    quad = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], dtype=np.float32).tobytes())
    vao = ctx.vertex_array(program, [(quad, "2f", "grader_xy")])
    try:
        fbo.use()
        vao.render(mode=ctx.TRIANGLE_STRIP)
        ctx.finish()
    finally:
        vao.release()
        quad.release()
        fbo.release()
        target.release()


def main() -> int:
    """Run the job read on stdin; return the exit status."""
    job = pickle.loads(sys.stdin.buffer.read())
    import numpy as np

    try:
        ctx = create_context()
    except RuntimeError as exc:
        sys.stderr.write(f"{exc}\n")
        return 4
    try:
        if job["stage"] == "compute":
            shader = ctx.compute_shader(job["source"])
        else:
            shader = ctx.program(vertex_shader=VERTEX, fragment_shader=job["source"])
    except Exception as exc:  # noqa: BLE001 - moderngl raises plain Exception for compile errors
        log = str(exc).strip().splitlines()
        first = next((line for line in log if "error" in line.lower()), log[0] if log else "")
        sys.stderr.write(first.strip() + "\n")
        return 3
    for name, value in job["uniforms"].items():
        if name in shader:
            shader[name].value = value
    inputs = np.frombuffer(job["inputs"], dtype=np.float32)
    rows, n_out = job["rows"], job["n_out"]
    buf_in = ctx.buffer(inputs.tobytes())
    buf_out = ctx.buffer(reserve=max(4, rows * n_out * 4))
    buf_in.bind_to_storage_buffer(0)
    buf_out.bind_to_storage_buffer(1)
    if "grader_rows" in shader:
        shader["grader_rows"] = rows
    if job["stage"] == "compute":
        shader.run(group_x=(rows + LOCAL_SIZE - 1) // LOCAL_SIZE)
    else:
        draw_rows(ctx, shader, rows)
    ctx.memory_barrier()
    ctx.finish()
    sys.stdout.buffer.write(buf_out.read()[: rows * n_out * 4])
    sys.stdout.buffer.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
