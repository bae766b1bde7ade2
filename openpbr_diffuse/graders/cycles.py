"""Blender Cycles (PyPI ``bpy``): the Diffuse BSDF's Oren–Nayar closure, measured by rendering.

Cycles' ``bsdf_oren_nayar`` (Diffuse BSDF node with roughness > 0) is FON plus an energy
compensation term.  It is graded by rendering (see :mod:`._cycles_scene`): BRDF values from a
plane lit by a zero-angle sun of strength 1 (pixel = f cos(theta_i); deterministic: a delta
light, a black world, one path vertex), directional albedo from the plane under a uniform white
world (pixel = E(mu_o); Monte Carlo, so its standard error is measured from the pixels).  The
render runs in a child Python (this one, or ``$OPENPBR_DIFFUSE_BPY_PYTHON``), so a crash in
Blender cannot take the grader down and ``bpy`` (which pins its own numpy) is imported only there.

Render budget (defaults): BRDF 2x2 px at 1 sample (exact up to float32), albedo 32x32 px at
256 samples per pixel (262 144 paths per row).
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from .errors import GraderUnavailable
from .subject import Subject

BUDGET = {
    "brdf_resolution": 2,
    "brdf_samples": 1,
    "albedo_resolution": 32,
    "albedo_samples": 256,
    "threads": 2,
    "seed": 0,
}
#: albedo rows with mu_o below this are not graded: Cycles samples the lobe with cosine sampling,
#: whose throughput variance grows at grazing view (standard error 3e-3 at mu = 0.001 with the
#: default budget, vs <= 1e-4 from mu = 0.1), and there every candidate formula tends to the
#: same E = rho anyway (1 - E_F -> 0), so those rows cannot separate them
ALBEDO_MU_MIN = 0.05
TOLERANCE = (3e-4, 1e-6)
TOLERANCE_REASON = (
    "Cycles renders: BRDF values free of noise (delta sun of angle 0, black world, one "
    "path vertex) but read through float32 scene transforms: |d mu_i| <~ 1.5e-7, i.e. "
    "1.5e-4 relative on f = pixel / mu_i at mu_i = 0.001 (measured); 3e-4 relative"
)


SCENE_SCRIPT = Path(__file__).with_name("_cycles_scene.py")
#: environment variable naming a Python interpreter that has bpy (bpy pins its own numpy and
#: CPython 3.11, so it often lives in a virtual environment of its own)
PYTHON_VARIABLE = "OPENPBR_DIFFUSE_BPY_PYTHON"
_INSTALL = (
    "bpy pins numpy<2, so give it a separate Python 3.11 (~0.8 GB): python3.11 -m venv bpy-env && "
    f"bpy-env/bin/pip install bpy && export {PYTHON_VARIABLE}=$PWD/bpy-env/bin/python"
)


def bpy_python() -> str:
    """The interpreter the renders run in: $OPENPBR_DIFFUSE_BPY_PYTHON, else this Python."""
    return os.environ.get(PYTHON_VARIABLE) or sys.executable


def _probe():
    code = (
        "import bpy, sys, os; h = os.path.join(bpy.utils.system_resource('SCRIPTS'), 'addons_core', "
        "'cycles', 'source', 'kernel', 'closure', 'bsdf_oren_nayar.h'); "
        "sys.stdout.write(bpy.app.version_string + '\\n' + (h if os.path.isfile(h) else ''))"
    )
    try:
        run = subprocess.run([bpy_python(), "-c", code], capture_output=True, text=True, check=False)
    except OSError as exc:
        raise GraderUnavailable(f"cannot run {bpy_python()} ({exc.strerror}): {_INSTALL}") from exc
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or ["?"])[-1]
        if "No module named 'bpy'" in last:
            raise GraderUnavailable(f"bpy (Blender as a Python module) is not installed in {bpy_python()}: {_INSTALL}")
        raise GraderUnavailable(f"bpy does not import in {bpy_python()}: {last}")
    lines = run.stdout.strip().splitlines()
    return lines[0], (Path(lines[1]) if len(lines) > 1 and lines[1] else None)


def bpy_version() -> str:
    """Blender version of the bpy the renders use (GraderUnavailable when there is none)."""
    return _probe()[0]


def render(rows: list[dict], budget: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Render job rows in a child Python with bpy; returns (mean (n,3), standard error (n,3))."""
    job = {**BUDGET, **(budget or {}), "rows": rows}
    with tempfile.TemporaryDirectory() as tmp:
        job_path, out_path = Path(tmp) / "job.json", Path(tmp) / "out"
        job_path.write_text(json.dumps(job))
        run = subprocess.run(
            [bpy_python(), str(SCENE_SCRIPT), str(job_path), str(out_path)], capture_output=True, text=True, check=False
        )
        if run.returncode != 0:
            tail = (run.stderr.strip().splitlines() or ["no output"])[-1]
            raise GraderUnavailable(f"the Cycles render failed: {tail}")
        data = np.load(f"{out_path}.npz")
        return data["mean"], data["stderr"]


def subject(source: Path | None = None, budget: dict | None = None) -> Subject:
    """Cycles from the installed ``bpy`` (``source`` is not used: the kernel ships in the wheel)."""
    version, kernel = _probe()
    last = {}  # the standard errors of the latest albedo render ("albedo_stderr"), read by grading

    def brdf(wi, wo, roughness, rho):
        wi, wo = np.asarray(wi, float).reshape(-1, 3), np.asarray(wo, float).reshape(-1, 3)
        n = wi.shape[0]
        roughness = np.broadcast_to(np.asarray(roughness, float), (n,))
        rho = np.broadcast_to(np.asarray(rho, float), (n, 3))
        out = np.full((n, 3), np.nan)  # NaN outside brdf_domain: not measurable by a render
        ok = brdf_domain(wi, wo)
        rows = [
            {
                "kind": "brdf",
                "wi": wi[k].tolist(),
                "wo": wo[k].tolist(),
                "roughness": float(roughness[k]),
                "rho": rho[k].tolist(),
            }
            for k in np.flatnonzero(ok)
        ]
        if rows:
            mean, _ = render(rows, budget)
            out[ok] = mean / wi[ok, 2:3]  # pixel = f cos(theta_i) for a sun of strength 1
        return out

    def albedo(mu, roughness, rho):
        mu = np.asarray(mu, float).reshape(-1)
        n = mu.shape[0]
        roughness = np.broadcast_to(np.asarray(roughness, float), (n,))
        rho = np.broadcast_to(np.asarray(rho, float), (n, 3))
        rows = [
            {"kind": "albedo", "mu": float(mu[k]), "roughness": float(roughness[k]), "rho": rho[k].tolist()}
            for k in range(n)
        ]
        mean, err = render(rows, budget)
        last["albedo_stderr"] = err
        return mean

    def brdf_domain(wi, wo):
        # a render cannot light or view a one-sided surface from below (Cycles shades back faces
        # as front faces): rows with a direction below the horizon are not measurable
        return (np.asarray(wi)[:, 2] > 0) & (np.asarray(wo)[:, 2] > 0)

    def albedo_domain(mu):
        return np.asarray(mu) >= ALBEDO_MU_MIN

    sha = hashlib.sha256(kernel.read_bytes()).hexdigest() if kernel else None
    return Subject(
        name="cycles",
        model="eon",
        tolerance=TOLERANCE,
        tolerance_reason=TOLERANCE_REASON,
        version={
            "blender": version,
            "source": str(kernel) if kernel else None,
            "files": ["kernel/closure/bsdf_oren_nayar.h"],
            "sha256": sha,
            "budget": {**BUDGET, **(budget or {})},
        },
        brdf=brdf,
        albedo=albedo,
        brdf_domain=brdf_domain,
        albedo_domain=albedo_domain,
        noise=last,
        notes=[
            "Diffuse BSDF node (Cycles bsdf_oren_nayar) rendered: sun of angle 0 for f, white world for E",
            "BRDF rows with a direction below the horizon cannot be rendered and are not graded",
            f"albedo rows with mu < {ALBEDO_MU_MIN} are not graded (cosine-sampling noise at grazing view, "
            "where every candidate tends to E = rho)",
        ],
    )
