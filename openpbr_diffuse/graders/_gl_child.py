"""Child process that runs one GLSL kernel on llvmpipe (started by glsl.Kernel.run under limits).

Reads a pickled job (shader text, stage, row sizes, uniforms, inputs) on stdin from its parent
and writes the float32 outputs on stdout; a shader that does not compile exits with status 3 and
one line on stderr.  Running the GL part here lets the parent kill a shader that never ends.
"""

from __future__ import annotations

import pickle
import sys


def main() -> int:
    """Run the job read on stdin; return the exit status."""
    job = pickle.loads(sys.stdin.buffer.read())
    import numpy as np

    from openpbr_diffuse.graders import glsl

    ctx = glsl.gl_context()
    try:
        if job["stage"] == "compute":
            shader = ctx.compute_shader(job["source"])
        else:
            shader = ctx.program(vertex_shader=glsl._VERTEX, fragment_shader=job["source"])
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
        shader.run(group_x=(rows + glsl.LOCAL_SIZE - 1) // glsl.LOCAL_SIZE)
    else:
        glsl._draw_rows(ctx, shader, rows)
    ctx.memory_barrier()
    ctx.finish()
    sys.stdout.buffer.write(buf_out.read()[: rows * n_out * 4])
    sys.stdout.buffer.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
