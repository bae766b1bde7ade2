"""Child process that runs GPU jobs for the graders: GLSL kernels on llvmpipe (``gl``) or WGSL
compute shaders through wgpu (``wgsl``), one job after the other, until its stdin closes.

The parent (:class:`.limits.Worker`) starts it once per API and process, under the limits of
user code and a supervisor (it dies with the parent), and sends each job as a frame: an 8-byte little-endian length, then a pickled dict.
The child answers each with a 12-byte header (int32 status, uint64 length) and the payload:

- status 0: the float32 outputs;
- status 1: the job failed otherwise (payload: the exception, as a traceback's last line);
- status 3: the shader does not compile (payload: one line of the compiler's log);
- status 4: no GL context / WebGPU adapter on this machine (payload: the reason).

A job that never ends is killed by the parent with every process of the child's run (the time
limit is per job); a child that dies (a crash, the memory limit) is started again for the next
job.  Keeping the context across jobs saves its set-up on every job but the first (the
measurements: docs/benchmarks/bench.md, "Measurements moved from the code").

The parent runs this file as a script (``CHILD``, through ``limits.script_command``), not as a
module of the package: it imports numpy and the GPU library only, not the package and numba.
The GL set-up the parent shares (the context, the fragment stage's row layout) is defined here
and imported by :mod:`.glsl`.

GLSL jobs: ``source``, ``stage`` ("compute" or "fragment"), ``n_out``, ``rows``, ``uniforms``,
``inputs`` (float32 bytes); or ``info`` (True), answered with "GL_RENDERER / GL_VERSION".
WGSL jobs: ``source``, ``n_in``, ``n_out``, ``rows``, ``inputs``; the shader reads ``grader_in`` (binding 0) and writes ``grader_out`` (binding 1), ``WORKGROUP``
rows per workgroup.  On a machine without a GPU, wgpu's Vulkan backend runs on Mesa's lavapipe
(Debian ``mesa-vulkan-drivers``).
"""

from __future__ import annotations

import os
import pickle
import struct
import sys
from pathlib import Path
from typing import Any

#: this file, which the parent runs as a script
CHILD = Path(__file__).resolve()
#: compute shader work-group size (rows per group), GLSL
LOCAL_SIZE = 64
#: width of the fragment stage's target: row = y * FRAGMENT_WIDTH + x
FRAGMENT_WIDTH = 256
#: rows per workgroup, WGSL
WORKGROUP = 64
VERTEX = """#version 430
in vec2 grader_xy;
void main() { gl_Position = vec4(grader_xy, 0.0, 1.0); }
"""
#: what to install when there is no OpenGL 4.3 context through EGL
NO_CONTEXT = "install Mesa's software driver, e.g. apt-get install libgl1-mesa-dri libegl1 libegl-mesa0"
#: the statuses of an answer
OK, FAILED, NO_COMPILE, NO_DEVICE = 0, 1, 3, 4
#: the frame headers: a job's length; an answer's status and length
JOB_HEADER = struct.Struct("<Q")
ANSWER_HEADER = struct.Struct("<iQ")


class Unavailable(Exception):
    """The job cannot run here (status ``NO_DEVICE``) or does not compile (``NO_COMPILE``)."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


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


def _first_error(text: str, default: str) -> str:
    lines = [line.strip() for line in str(text).splitlines() if line.strip()]
    return next((line for line in lines if "error" in line.lower()), lines[0] if lines else default)


class GL:
    """Runs GLSL jobs on one moderngl context, made on the first job."""

    def __init__(self) -> None:
        self.ctx: Any = None

    def run(self, job: dict) -> bytes:
        if self.ctx is None:
            try:
                self.ctx = create_context()
            except RuntimeError as exc:
                raise Unavailable(NO_DEVICE, str(exc)) from exc
        ctx = self.ctx
        if job.get("info"):  # the context's renderer and version
            return f"{ctx.info['GL_RENDERER']} / {ctx.info['GL_VERSION']}".encode()
        try:
            if job["stage"] == "compute":
                shader = ctx.compute_shader(job["source"])
            else:
                shader = ctx.program(vertex_shader=VERTEX, fragment_shader=job["source"])
        except Exception as exc:  # noqa: BLE001 - moderngl raises plain Exception for compile errors
            raise Unavailable(NO_COMPILE, _first_error(str(exc), "compile error")) from exc
        rows, n_out = job["rows"], job["n_out"]
        buf_in = ctx.buffer(job["inputs"])
        buf_out = ctx.buffer(reserve=max(4, rows * n_out * 4))
        try:
            for name, value in job["uniforms"].items():
                if name in shader:
                    shader[name].value = value
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
            return buf_out.read()[: rows * n_out * 4]
        finally:
            buf_in.release()
            buf_out.release()
            shader.release()


class WGSL:
    """Runs WGSL jobs on one wgpu device, requested on the first job."""

    def __init__(self) -> None:
        self.device: Any = None

    def run(self, job: dict) -> bytes:
        import numpy as np
        import wgpu  # type: ignore[import-untyped]

        if self.device is None:
            os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")
            try:
                adapter = wgpu.gpu.request_adapter_sync(power_preference="low-power")
                self.device = adapter.request_device_sync()
            except Exception as exc:  # noqa: BLE001 - wgpu raises several kinds
                first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                raise Unavailable(
                    NO_DEVICE,
                    f"no WebGPU adapter ({first}): install Mesa's Vulkan driver, apt-get install mesa-vulkan-drivers",
                ) from exc
        device = self.device
        try:
            module = device.create_shader_module(code=job["source"])
            pipe = device.create_compute_pipeline(layout="auto", compute={"module": module, "entry_point": "main"})
        except Exception as exc:  # noqa: BLE001
            raise Unavailable(NO_COMPILE, _first_error(str(exc), "compile error")) from exc
        rows, n_out = job["rows"], job["n_out"]
        padded = -(-rows // WORKGROUP) * WORKGROUP
        data = np.zeros(padded * job["n_in"], np.float32)
        data[: rows * job["n_in"]] = np.frombuffer(job["inputs"], np.float32)
        buf_in = device.create_buffer_with_data(data=data.tobytes(), usage=wgpu.BufferUsage.STORAGE)
        buf_out = device.create_buffer(
            size=padded * n_out * 4, usage=wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC
        )
        try:  # the device outlives the job: its buffers are released whatever happens
            group = device.create_bind_group(
                layout=pipe.get_bind_group_layout(0),
                entries=[
                    {"binding": 0, "resource": {"buffer": buf_in}},
                    {"binding": 1, "resource": {"buffer": buf_out}},
                ],
            )
            encoder = device.create_command_encoder()
            compute = encoder.begin_compute_pass()
            compute.set_pipeline(pipe)
            compute.set_bind_group(0, group)
            compute.dispatch_workgroups(padded // WORKGROUP)
            compute.end()
            device.queue.submit([encoder.finish()])
            return bytes(device.queue.read_buffer(buf_out))[: rows * n_out * 4]
        finally:
            buf_in.destroy()
            buf_out.destroy()


def _read(stream: Any, n: int) -> bytes | None:
    """n bytes from ``stream``, or None at the end of the input (the parent closed it)."""
    data = stream.read(n)
    if len(data) < n:
        return None
    return data


def serve(api: Any, jobs: Any, answers: Any) -> int:
    """Answer every job frame read from ``jobs`` on ``answers`` until the input ends."""
    while True:
        head = _read(jobs, JOB_HEADER.size)
        if head is None:
            return 0
        (length,) = JOB_HEADER.unpack(head)
        body = _read(jobs, length)
        if body is None:
            return 0
        try:
            status, payload = OK, api.run(pickle.loads(body))
        except Unavailable as exc:
            status, payload = exc.status, str(exc).encode()
        except Exception as exc:  # noqa: BLE001 - any other failure of a job, as a traceback's last line
            status, payload = FAILED, f"{type(exc).__name__}: {exc}".encode()
        answers.write(ANSWER_HEADER.pack(status, len(payload)) + payload)
        answers.flush()


def main(argv: list[str]) -> int:
    """``gl`` or ``wgsl``: serve that API's jobs on stdin / stdout."""
    api = {"gl": GL, "wgsl": WGSL}[argv[1]]()
    # the answers go to a private copy of stdout; what the GPU libraries print to file
    # descriptor 1 goes to stderr instead of into the frames
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    return serve(api, sys.stdin.buffer, answers)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
