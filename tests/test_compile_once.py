"""What a first call compiles: one driver specialisation per model, verb and dtype whatever the
layout of the caller's arrays, only the asked-for model's kernels, and no simulator in
``report --quick``.

Each test runs its calls in a fresh process with an empty numba cache (``NUMBA_CACHE_DIR`` a new
folder), so that what it counts was compiled by those calls and nothing else.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: Records every compilation of the child process: the function's module and name, and the
#: int constants its closure holds (a model driver's model id and channel variant).
_LISTEN = r"""
import json, sys
from numba.core import event

COMPILED = []


class _Listener(event.Listener):
    def on_start(self, e):
        pass

    def on_end(self, e):
        f = getattr(e.data["dispatcher"], "py_func", None)
        if f is None:
            return
        cells = {}
        for name, cell in zip(f.__code__.co_freevars, f.__closure__ or ()):
            try:
                v = cell.cell_contents
            except ValueError:
                continue
            if isinstance(v, (bool, int)):
                cells[name] = v
        COMPILED.append({"module": f.__module__, "name": f.__qualname__, "cells": cells, "args": str(e.data["args"])})


event.register("numba:compile", _Listener())
"""


def _run(body: str, tmp_path, *argv) -> dict:
    """Run ``body`` after the listener in a child with an empty numba cache; its JSON result."""
    env = dict(
        os.environ,
        NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"),
        PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
    )
    out = tmp_path / "out.json"
    code = _LISTEN + body + f"\njson.dump(RESULT, open({str(out)!r}, 'w'))\n"
    done = subprocess.run(
        [sys.executable, "-c", code, *argv], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(out.read_text())


_LAYOUTS = r"""
import numpy as np
import openpbr_diffuse as od
from openpbr_diffuse.models import _kernels as mk
from openpbr_diffuse.sampling import _kernels as sk

rng = np.random.default_rng(3)
n = 40
wi = rng.normal(size=(2 * n, 3)); wi[:, 2] = np.abs(wi[:, 2]); wi /= np.linalg.norm(wi, axis=1, keepdims=True)
wo = wi[::-1].copy()
r = rng.uniform(0.0, 1.0, 2 * n)
rho = rng.uniform(0.0, 1.0, (2 * n, 3))
frozen = [a.copy() for a in (wi, wo, r, rho)]
for a in frozen:
    a.flags.writeable = False
fortran = [np.asfortranarray(a) for a in (wi, wo, r, rho)]
variants = [
    (wi[:n], wo[:n], r[:n], rho[:n]),                 # C-contiguous
    (wi[::2], wo[::2], r[::2], rho[::2]),             # strided views
    tuple(frozen),                                    # read-only
    tuple(fortran),                                   # Fortran order
    (wi[0], wo[0], 0.5, rho[0]),                      # one row
    (wi[:n], wo[0], np.float64(0.5), rho[0]),         # tiled direction, numpy scalar
    (wi[:n, None], wo[None, :n], r[:n, None], rho[:n, None]),  # broadcast outer product
    (wi[:n].tolist(), wo[:n].tolist(), 1, [0.5, 0.25, 1]),     # lists and Python ints
]
for a, b, c, d in variants:
    od.evaluate("lambert", a, b, c, d)
    od.directional_albedo("lambert", np.abs(np.asarray(b, float)[..., 2]), c, d)
    od.sample("cosine", b, c, np.full(np.shape(b)[:-1] + (2,), 0.25))
f64 = {
    "evaluate": len(mk.eval_driver(mk.LAMBERT, 3).signatures),
    "albedo": len(mk.albedo_driver(mk.LAMBERT, 3).signatures),
    "sample": len(sk.sample_driver(sk.COSINE).signatures),
}
f32 = [np.asarray(x, np.float32) for x in (wi[:n], wo[:n], r[:n], rho[:n])]
od.evaluate("lambert", *f32)
od.evaluate("lambert", f32[0][::2], f32[1][::2], f32[2][::2], f32[3][::2])
od.directional_albedo("lambert", f32[1][:, 2], f32[2], f32[3])
od.sample("cosine", f32[1], f32[2], np.full((n, 2), 0.25, np.float32))
RESULT = {
    "float64": f64,
    "both": {
        "evaluate": len(mk.eval_driver(mk.LAMBERT, 3).signatures),
        "albedo": len(mk.albedo_driver(mk.LAMBERT, 3).signatures),
        "sample": len(sk.sample_driver(sk.COSINE).signatures),
    },
    "drivers": sorted({(c["name"], json.dumps(c["cells"], sort_keys=True)) for c in COMPILED if c["name"].endswith("drive")}),
}
"""


def test_one_driver_specialisation_per_dtype_whatever_the_layout(tmp_path):
    """C-contiguous, strided, read-only and Fortran-order arrays, tiled and broadcast inputs,
    scalars, lists and Python ints all run the same compiled driver: one signature for float64
    and a second only once float32 is used."""
    got = _run(_LAYOUTS, tmp_path)
    assert got["float64"] == {"evaluate": 1, "albedo": 1, "sample": 1}
    assert got["both"] == {"evaluate": 2, "albedo": 2, "sample": 2}
    # one driver per verb and model (and one channel variant: every call above has C = 3)
    names = [name for name, _ in got["drivers"]]
    assert len(names) == 3, got["drivers"]


_ALBEDO_EON = r"""
from openpbr_diffuse.cli.main import main
rc = main(["albedo", "eon", "--roughness", "0.5", "--mu", "0.5"])
RESULT = {"rc": rc, "compiled": COMPILED}
"""

#: Kernels of the models other than EON that EON's directional albedo does not use (EON's
#: closed form uses FON's E_F and with it the QON/FON G functions, which are EON's own kernels
#: as well).
_OTHER_MODELS = {
    "openpbr_diffuse.models.lambert",
    "openpbr_diffuse.models.gotanda",
    "openpbr_diffuse.models.fujii",
    "openpbr_diffuse.models.full_on",
    "openpbr_diffuse.models.van_ouwerkerk",
}


def test_albedo_eon_compiles_only_eon(tmp_path):
    """The first ``albedo eon`` compiles one driver, EON's, and no other model's kernels
    (a run-time ``if model == ...`` chain typed every model's branch)."""
    got = _run(_ALBEDO_EON, tmp_path)
    assert got["rc"] in (0, None)
    from openpbr_diffuse.models.registry import INFO

    drivers = [c for c in got["compiled"] if c["name"].endswith("drive")]
    assert [d["cells"]["model"] for d in drivers] == [INFO["eon"].id], drivers
    others = sorted({c["module"] + "." + c["name"] for c in got["compiled"] if c["module"] in _OTHER_MODELS})
    assert not others
    qon_only = {"qon_albedo", "qon_average_albedo", "qon_terms", "fon_albedo", "fon_terms"}
    assert not [c for c in got["compiled"] if c["name"] in qon_only]
    assert not [c for c in got["compiled"] if c["module"].startswith("openpbr_diffuse.nodes")]


_QUICK_SIMULATION = r"""
import tempfile
from pathlib import Path
from openpbr_diffuse.report.model import Context
from openpbr_diffuse.report.runner import run_section

ctx = Context(image_dir=Path(tempfile.mkdtemp()), quick=True)
runs = [run_section(key, ctx) for key in ("simulation", "layered")]
RESULT = {
    "compiled": sorted({c["module"] for c in COMPILED}),
    "sections": [
        {"key": r.result.key, "status": r.status, "not_run": r.result.not_run,
         "checks": [(c.id, c.status, c.not_run) for c in r.result.checks]}
        for r in runs
    ],
}
"""


def test_quick_report_runs_no_simulator(tmp_path):
    """``report --quick`` leaves the live simulations to the full report: the simulation and
    layered sections compile nothing of ``openpbr_diffuse.simulation``, and their live checks
    are listed as not run in --quick (never passed)."""
    from openpbr_diffuse.report.model import QUICK_NOT_RUN

    got = _run(_QUICK_SIMULATION, tmp_path)
    assert not [m for m in got["compiled"] if m.startswith("openpbr_diffuse.simulation")], got["compiled"]
    sim, layered = got["sections"]
    assert sim["status"] == "pass"  # the checks against the shipped tables ran
    live = [c for c in sim["checks"] if c[2] == QUICK_NOT_RUN]
    assert len(live) == 4 and all(status == "not run" for _, status, _ in live)
    assert layered["status"] == "not run" and layered["not_run"] == QUICK_NOT_RUN
    assert layered["checks"] and all(c[1] == "not run" and c[2] == QUICK_NOT_RUN for c in layered["checks"])


_KERNEL_BOTH_WAYS = r"""
import math
import numpy as np
from openpbr_diffuse import directional_albedo
from openpbr_diffuse._jit import acos
from openpbr_diffuse.models import eon

order = sys.argv[1]
RESULT = {}
if order == "python-first":
    RESULT["python"] = [acos(0.3), eon.rho_ms(0.5, 0.7)]
RESULT["compiled"] = float(np.ravel(directional_albedo("eon", np.array([0.5]), 0.7, 0.5))[0])
if order == "compiled-first":
    RESULT["python"] = [acos(0.3), eon.rho_ms(0.5, 0.7)]
RESULT["reference"] = [math.acos(0.3), eon.rho_ms.py_func(0.5, 0.7)]
RESULT["options"] = {k: v for k, v in eon.rho_ms.targetoptions.items() if k.startswith("no_c")}
"""


def test_kernels_called_from_python_and_from_compiled_code_share_a_cache(tmp_path):
    """A kernel is compiled for compiled callers without numba's CPython entry point; a call
    from Python uses a twin compiled with one.  Both orders of first use, in one cache that
    the second process reads: no process may load the other kind's machine code (calling an
    entry point that is not there would crash the interpreter)."""
    first = _run(_KERNEL_BOTH_WAYS, tmp_path, "python-first")
    again = _run(_KERNEL_BOTH_WAYS, tmp_path, "compiled-first")
    for r in (first, again):
        assert r["options"] == {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}
        assert abs(r["python"][0] - r["reference"][0]) <= 4e-16
        assert r["python"][1] == r["reference"][1]
        assert r["compiled"] == again["compiled"] == first["compiled"]
    assert (first["compiled"] > 0.0) and (first["compiled"] < 0.5)


_EVALUATE_A_MATERIAL = r"""
from openpbr_diffuse.readers import load_materials
from openpbr_diffuse.readers.evaluate import evaluate
from openpbr_diffuse.readers.preview import render_image

m = next(m for m in load_materials(sys.argv[1]) if m.supported)
r = evaluate(m, [10.0, 30.0], [20.0, 40.0], [180.0, 90.0])
render_image(m, 16, supersample=1)
RESULT = {
    "runners": sorted(
        {c["name"].split(".")[0] for c in COMPILED if c["module"].endswith("_surface_drivers") and "_run." in c["name"]}
    ),
    "albedo": r["albedo"],
    "brdf": r["brdf"],
}
"""


def test_a_materials_evaluation_compiles_one_surface_runner(tmp_path):
    """The readers' evaluation of a material and its preview (BSDF, lobes, albedo) compile the
    one ``lobes`` runner (the lobes and, in the same pass, the BSDF), not the ``eval`` and
    ``albedo`` runners too, and give what those verbs give."""
    from openpbr_diffuse.readers import load_materials
    from openpbr_diffuse.readers.evaluate import directions

    path = str(ROOT / "materials" / "clay_rough.mtlx")
    r = _run(_EVALUATE_A_MATERIAL, tmp_path, path)
    assert r["runners"] == ["_lobes_run"]
    node = next(m for m in load_materials(path) if m.supported).node()
    wi, wo = directions(np.array([10.0, 30.0]), np.array([20.0, 40.0]), np.array([180.0, 90.0]))
    np.testing.assert_allclose(r["albedo"], node.albedo(wo), rtol=1e-13)
    np.testing.assert_allclose(r["brdf"], node.eval(wi, wo), rtol=1e-13)


_THREE_DIFFUSE_MODELS = r"""
import numpy as np
from openpbr_diffuse import OpenPBRSurface

rng = np.random.default_rng(5)
wi, wo = rng.normal(size=(2, 300, 3))
wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
wi /= np.linalg.norm(wi, axis=1)[:, None]
wo /= np.linalg.norm(wo, axis=1)[:, None]
base = dict(base_color=(0.8, 0.5, 0.3), base_diffuse_roughness=0.7, base_metalness=0.3, specular_roughness=0.4)
out = {}
for model in ("eon", "qon", "lambert"):
    s = OpenPBRSurface(**base, diffuse_model=model)
    lobes, f = s.lobes_and_eval(wi, wo)
    out[model] = {"f": f.tolist(), "E": sum(l.weight * l.albedo for l in lobes).tolist()}
RESULT = {
    "lobes_runners": [c["cells"] for c in COMPILED if c["name"].startswith("_lobes_run.")],
    "out": out,
    "wi": wi.tolist(),
    "wo": wo.tolist(),
}
"""


def test_one_lobes_runner_serves_every_diffuse_model(tmp_path):
    """Materials of the same lobe set with EON, QON and Lambert diffuse lobes compile one
    ``lobes`` runner (the diffuse model is a run-time argument of it), and each model's
    lobes and BSDF equal those of the ``eval`` and ``albedo`` runners, which are compiled
    with the model a constant (a second compilation of the passes)."""
    from openpbr_diffuse import OpenPBRSurface

    r = _run(_THREE_DIFFUSE_MODELS, tmp_path)
    assert len(r["lobes_runners"]) == 1, r["lobes_runners"]
    wi, wo = np.array(r["wi"]), np.array(r["wo"])
    base = dict(base_color=(0.8, 0.5, 0.3), base_diffuse_roughness=0.7, base_metalness=0.3, specular_roughness=0.4)
    for model, got in r["out"].items():
        s = OpenPBRSurface(**base, diffuse_model=model)
        np.testing.assert_allclose(got["f"], s.eval(wi, wo), rtol=1e-13, atol=1e-300, err_msg=model)
        np.testing.assert_allclose(got["E"], s.albedo(wo), rtol=1e-13, err_msg=model)
    # the three models differ (the run-time argument reaches the diffuse lobe)
    assert not np.allclose(r["out"]["eon"]["f"], r["out"]["qon"]["f"])
    assert not np.allclose(r["out"]["qon"]["f"], r["out"]["lambert"]["f"])


def test_spectral_channel_counts_share_one_albedo_driver():
    """A model's albedo driver for any channel count other than 1 and 3 is one compiled
    function (the colour-shift section's 81- and 85-sample spectra)."""
    from openpbr_diffuse.models import _kernels as mk

    assert mk.albedo_driver(mk.EON, 81) is mk.albedo_driver(mk.EON, 85) is mk.albedo_driver(mk.EON, 7)
    assert mk.eval_driver(mk.EON, 81) is mk.eval_driver(mk.EON, 85)
    assert mk.albedo_driver(mk.EON, 3) is not mk.albedo_driver(mk.EON, 81)
    assert mk.albedo_driver(mk.EON, 1) is not mk.albedo_driver(mk.EON, 3)


_LAYERED_OVER_LAMBERT = r"""
from openpbr_diffuse.simulation.layered import LayeredSurface, simulate_layered_albedo

for surface in (LayeredSurface("smooth", 1.5, coat_color=0.8), LayeredSurface("ggx", 1.5, 0.25)):
    simulate_layered_albedo(surface, [0.4], rho=[0.8, 1.0], paths=500, seed=1, workers=1)
RESULT = {"compiled": sorted({c["name"] for c in COMPILED})}
"""


def test_a_layered_walk_compiles_its_own_base_only(tmp_path):
    """The layered simulator's chunk kernel is compiled per base: walks over a Lambertian base
    (smooth and rough interfaces) compile neither the Smith microsurface's walk nor the EON
    sampler."""
    compiled = _run(_LAYERED_OVER_LAMBERT, tmp_path)["compiled"]
    assert any(n.startswith("chunk_kernel.") for n in compiled), compiled
    assert not [n for n in compiled if n in ("smith_base", "eon_sample")], compiled
