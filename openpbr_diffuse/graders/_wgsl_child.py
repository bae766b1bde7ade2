"""Child process that runs one WGSL compute shader through wgpu (started under limits).

Reads a pickled job (``source``, ``n_out``, ``rows``, ``inputs`` float32 bytes) on stdin and writes
the float32 outputs on stdout.  The shader reads ``grader_in`` (binding 0) and writes
``grader_out`` (binding 1), 64 rows per workgroup.  On a machine without a GPU, wgpu's Vulkan
backend runs on Mesa's lavapipe (llvmpipe for Vulkan, Debian ``mesa-vulkan-drivers``).  Exit
status 3 with one line on stderr: no adapter, or the shader does not compile.  ``wgpu`` is a
dependency of the package's ``test`` extra; without it the import fails and the parent reports
the traceback's last line (``ModuleNotFoundError: No module named 'wgpu'``).
"""

from __future__ import annotations

import os
import pickle
import sys
from pathlib import Path

#: this file, which the parent runs as a script (``limits.script_command``): a run imports
#: numpy and wgpu, not the package and numba
CHILD = Path(__file__).resolve()
WORKGROUP = 64


def main() -> int:
    """Run the job read on stdin; return the exit status."""
    job = pickle.loads(sys.stdin.buffer.read())
    os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")
    import numpy as np
    import wgpu  # type: ignore[import-untyped]

    try:
        adapter = wgpu.gpu.request_adapter_sync(power_preference="low-power")
        device = adapter.request_device_sync()
    except Exception as exc:  # noqa: BLE001 - wgpu raises several kinds
        sys.stderr.write(
            f"no WebGPU adapter ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__}): "
            "install Mesa's Vulkan driver, apt-get install mesa-vulkan-drivers\n"
        )
        return 3
    try:
        module = device.create_shader_module(code=job["source"])
        pipe = device.create_compute_pipeline(layout="auto", compute={"module": module, "entry_point": "main"})
    except Exception as exc:  # noqa: BLE001
        lines = [line for line in str(exc).splitlines() if line.strip()]
        first = next((line for line in lines if "error" in line.lower()), lines[0] if lines else "compile error")
        sys.stderr.write(first.strip() + "\n")
        return 3
    rows, n_out = job["rows"], job["n_out"]
    padded = -(-rows // WORKGROUP) * WORKGROUP
    data = np.zeros(padded * job["n_in"], np.float32)
    data[: rows * job["n_in"]] = np.frombuffer(job["inputs"], np.float32)
    buf_in = device.create_buffer_with_data(data=data.tobytes(), usage=wgpu.BufferUsage.STORAGE)
    buf_out = device.create_buffer(size=padded * n_out * 4, usage=wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC)
    group = device.create_bind_group(
        layout=pipe.get_bind_group_layout(0),
        entries=[{"binding": 0, "resource": {"buffer": buf_in}}, {"binding": 1, "resource": {"buffer": buf_out}}],
    )
    encoder = device.create_command_encoder()
    compute = encoder.begin_compute_pass()
    compute.set_pipeline(pipe)
    compute.set_bind_group(0, group)
    compute.dispatch_workgroups(padded // WORKGROUP)
    compute.end()
    device.queue.submit([encoder.finish()])
    out = device.queue.read_buffer(buf_out)
    sys.stdout.buffer.write(bytes(out)[: rows * n_out * 4])
    sys.stdout.buffer.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
