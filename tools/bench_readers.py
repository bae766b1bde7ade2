"""Benchmark of the material readers: a generated stage of N materials, and a real-world corpus.

    python tools/bench_readers.py [--quick] [--materials N]
    python tools/bench_readers.py --corpus [--root DIR]
    python tools/bench_readers.py --corpus-totals [--root DIR] [--write docs/guide/materials.md]

The stage (written with the Sdf API into a temporary .usdc, not timed) holds N materials:
70 % OpenPBR (half of them with base_color and roughness through Material interface inputs),
20 % UsdPreviewSurface, 10 % Standard Surface, with random colours and roughness (seeded).
Timed (wall clock, and the process's CPU time, which a busy machine inflates less):
``load_materials`` (open, resolve every input with provenance, map onto the library
node) and ``evaluate_many`` (BRDF, albedo, diffuse weight and probability of every material
at one direction pair, vectorised per node group).  Target: < 10 s for 10,000 materials.

``--corpus`` times the sweep of a folder of real material files (default: the shared
real-world corpus, MaterialX's test suite and examples, usd-wg/assets, kwokcb/materialxusd):
``load_materials`` on every .mtlx / .usd* file and ``evaluate_many`` on its supported
materials, warm (a first sweep loads the libraries, the numba kernels and the texture cache;
the second is timed), and one file's ``openpbr-diffuse eval`` in a subprocess (the second of
two runs; wall clock and the child's CPU time).  Targets: sweep < 3 min, one eval < 2 s.

``--corpus-totals`` prints the sweep's totals (files, materials, supported by shader id,
unsupported by id, failures with reasons) as the Markdown block of docs/guide/materials.md;
``--write FILE`` replaces that block in FILE (between the ``corpus-totals`` markers).  The
corpus sweep test checks the block against the same function.
"""

import argparse
import collections
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
import traceback
import warnings
from pathlib import Path

import numpy as np

TARGET_S = 10.0
CORPUS_TARGET_S = 180.0
EVAL_TARGET_S = 2.0
#: The shared real-world corpus (used when --root is not given).
CORPUS = (
    Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or Path(__file__).resolve().parents[1].parent / "shared")
    / "corpus"
    / "realworld"
)
#: Files whose ``eval`` is timed (relative to the corpus root).
EVAL_FILES = (
    "usd-wg-assets/full_assets/StandardShaderBall/layers/environment.usda",
    "MaterialX/resources/Materials/Examples/StandardSurface/standard_surface_chrome.mtlx",
)
BEGIN, END = "<!-- corpus-totals:begin -->", "<!-- corpus-totals:end -->"


def make_stage(path, n, seed=10):
    """Write a stage with ``n`` materials to ``path`` (a .usdc)."""
    from pxr import Sdf, Usd

    rng = np.random.default_rng(seed)
    stage = Usd.Stage.CreateNew(path)
    layer = stage.GetRootLayer()
    kinds = rng.choice(3, size=n, p=[0.7, 0.2, 0.1])
    colours = rng.uniform(0.05, 0.95, size=(n, 3))
    rough = rng.uniform(0.0, 1.0, size=n)
    with Sdf.ChangeBlock():
        Sdf.CreatePrimInLayer(layer, "/Looks").specifier = Sdf.SpecifierDef
        for i in range(n):
            mpath = f"/Looks/M{i:05d}"
            mat = Sdf.CreatePrimInLayer(layer, mpath)
            mat.specifier, mat.typeName = Sdf.SpecifierDef, "Material"
            sh = Sdf.CreatePrimInLayer(layer, mpath + "/S")
            sh.specifier, sh.typeName = Sdf.SpecifierDef, "Shader"
            sid = ("ND_open_pbr_surface_surfaceshader", "UsdPreviewSurface", "ND_standard_surface_surfaceshader")[
                kinds[i]
            ]
            Sdf.AttributeSpec(sh, "info:id", Sdf.ValueTypeNames.Token, variability=Sdf.VariabilityUniform).default = sid
            out_name = "outputs:surface" if kinds[i] == 1 else "outputs:out"
            Sdf.AttributeSpec(sh, out_name, Sdf.ValueTypeNames.Token)
            surf = Sdf.AttributeSpec(
                mat, "outputs:surface" if kinds[i] == 1 else "outputs:mtlx:surface", Sdf.ValueTypeNames.Token
            )
            surf.connectionPathList.explicitItems = [Sdf.Path(f"{mpath}/S.{out_name}")]
            colour = tuple(float(x) for x in colours[i])
            names = {
                0: ("base_color", "base_diffuse_roughness", "specular_roughness"),
                1: ("diffuseColor", None, "roughness"),
                2: ("base_color", "diffuse_roughness", "specular_roughness"),
            }[kinds[i]]
            via_interface = kinds[i] == 0 and i % 2 == 0
            if via_interface:
                a = Sdf.AttributeSpec(mat, "inputs:colour", Sdf.ValueTypeNames.Color3f)
                a.default = colour
                c = Sdf.AttributeSpec(sh, f"inputs:{names[0]}", Sdf.ValueTypeNames.Color3f)
                c.connectionPathList.explicitItems = [Sdf.Path(f"{mpath}.inputs:colour")]
            else:
                Sdf.AttributeSpec(sh, f"inputs:{names[0]}", Sdf.ValueTypeNames.Color3f).default = colour
            if names[1]:
                Sdf.AttributeSpec(sh, f"inputs:{names[1]}", Sdf.ValueTypeNames.Float).default = float(rough[i])
            Sdf.AttributeSpec(sh, f"inputs:{names[2]}", Sdf.ValueTypeNames.Float).default = 0.3 + 0.5 * float(rough[i])
    stage.Save()
    return path


def run(n):
    from openpbr_diffuse.readers import load_materials
    from openpbr_diffuse.readers.evaluate import evaluate_many

    with tempfile.TemporaryDirectory() as tmp:
        path = make_stage(os.path.join(tmp, "bench.usdc"), n)
        # warm-up: library loads, numba compilation (not what is measured)
        evaluate_many(load_materials(path, material="/Looks/M00000") + load_materials(path, material="/Looks/M00001"))
        c0, t0 = time.process_time(), time.perf_counter()
        mats = load_materials(path)
        c1, t1 = time.process_time(), time.perf_counter()
        res = evaluate_many(mats, 30.0, 45.0, 180.0)
        c2, t2 = time.process_time(), time.perf_counter()
    assert len(mats) == n and all(m.supported for m in mats)
    assert np.all(np.isfinite(res["brdf"]))
    return t1 - t0, t2 - t1, (c1 - c0) + (c2 - c1)


def rows(quick=False, n=None):
    n = n or (1000 if quick else 10000)
    t_resolve, t_eval, cpu = run(n)
    total = t_resolve + t_eval
    target = TARGET_S * n / 10000
    return [
        {
            "name": f"readers: resolve + evaluate {n} materials, CPU time of the process",
            "value": round(cpu, 3),
            "unit": "s",
            "target": None,
            "ok": True,
        },
        {
            "name": f"readers: resolve {n} USD materials",
            "value": round(t_resolve, 3),
            "unit": "s",
            "target": None,
            "ok": True,
        },
        {
            "name": f"readers: evaluate {n} materials (evaluate_many)",
            "value": round(t_eval, 3),
            "unit": "s",
            "target": None,
            "ok": True,
        },
        {
            "name": f"readers: resolve + evaluate {n} materials",
            "value": round(total, 3),
            "unit": "s",
            "target": f"< {target:g}",
            "ok": total < target,
        },
    ]


# ----------------------------------------------------------------------------- corpus sweep
def corpus_files(root):
    """Every material file (.mtlx .usda .usd .usdc .usdz) under ``root``, sorted."""
    from openpbr_diffuse.readers.api import MATERIAL_SUFFIXES

    return sorted(p for p in Path(root).rglob("*") if p.suffix.lower() in MATERIAL_SUFFIXES and p.is_file())


def sweep_file(path, evaluate=True):
    """Read one file as a pipeline would: ``load_materials`` and ``evaluate_many``.

    Returns a dict: ``file``; ``rejected`` (the one-line reason when the reader refuses the
    file as a whole, else None); ``traceback`` (any other exception, else None);
    ``materials``: [(path, shader id, supported, error, output type or None)], the output type
    set for a renderable MaterialX output that is not a surface shader; ``finite``: whether
    every supported material's BRDF came out finite.
    """
    from openpbr_diffuse.readers import load_materials
    from openpbr_diffuse.readers.evaluate import evaluate_many
    from openpbr_diffuse.readers.materialx import NOT_A_SHADER

    rec = {"file": str(path), "rejected": None, "traceback": None, "materials": [], "finite": True}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mats = load_materials(path)
            sup = [m for m in mats if m.supported]
            if evaluate and sup:
                rec["finite"] = bool(np.all(np.isfinite(evaluate_many(sup)["brdf"])))
    except (ValueError, OSError, TypeError) as exc:
        rec["rejected"] = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return rec
    except Exception:
        rec["traceback"] = traceback.format_exc()
        return rec
    for m in mats:
        out = None
        if m.unsupported and NOT_A_SHADER in m.unsupported[0]:
            found = re.search(r": an? (\w+) output, ", m.unsupported[0])
            out = found.group(1) if found else "?"
        rec["materials"].append((m.path, m.shader_id, m.supported, m.error, out))
    return rec


def sweep(root=CORPUS, evaluate=True):
    """``sweep_file`` of every material file under ``root``."""
    return [sweep_file(f, evaluate) for f in corpus_files(root)]


def _reason(error, file):
    """A failure's reason without its file and element path (for counting)."""
    text = error[len(file) + 2 :] if error.startswith(file + ": ") else error
    parts = text.split(": ", 1)
    if len(parts) == 2 and " " not in parts[0]:
        text = parts[1]
    return text.split(";")[0]


def totals(records):
    """The sweep's totals: files, rejected files, tracebacks, materials, supported by shader
    id, unsupported shaders by id, non-shader outputs by type, failures by reason."""
    t = {
        "files": len(records),
        "rejected": [r["file"] for r in records if r["rejected"]],
        "tracebacks": [r["file"] for r in records if r["traceback"]],
        "materials": 0,
        "supported": collections.Counter(),
        "unsupported": collections.Counter(),
        "outputs": collections.Counter(),
        "failures": collections.Counter(),
    }
    for r in records:
        for _path, sid, supported, error, out in r["materials"]:
            t["materials"] += 1
            if error:
                t["failures"][_reason(error, r["file"])] += 1
            elif supported:
                t["supported"][sid] += 1
            elif out:
                t["outputs"][out] += 1
            else:
                t["unsupported"][sid or "(no surface shader connected)"] += 1
    return t


def _counts(counter):
    return ", ".join(f"`{k}` {v}" for k, v in sorted(counter.items(), key=lambda kv: (-kv[1], kv[0])))


def totals_markdown(t):
    """The Markdown block of the totals (what docs/guide/materials.md holds between the markers)."""
    n_sup, n_uns, n_out, n_fail = (sum(t[k].values()) for k in ("supported", "unsupported", "outputs", "failures"))
    lines = [
        BEGIN,
        "| files | rejected | tracebacks | materials | supported | unsupported shaders | non-shader outputs | failed |",
        "|---|---|---|---|---|---|---|---|",
        f"| {t['files']} | {len(t['rejected'])} | {len(t['tracebacks'])} | {t['materials']} | {n_sup} | {n_uns} "
        f"| {n_out} | {n_fail} |",
        "",
        f"- supported, by shader id: {_counts(t['supported'])}",
        f"- unsupported, by shader id: {_counts(t['unsupported'])}",
        f"- renderable MaterialX outputs that are not surface shaders (listed unsupported), by type: "
        f"{_counts(t['outputs'])}",
        f"- failed (their own material only, with the reason): {_counts(t['failures']) or 'none'}",
        END,
    ]
    return "\n".join(lines)


def write_totals(doc, block):
    """Replace the block between the corpus-totals markers of ``doc`` (a Markdown file)."""
    text = Path(doc).read_text()
    i, j = text.index(BEGIN), text.index(END) + len(END)
    Path(doc).write_text(text[:i] + block + text[j:])


def _eval_once(path):
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "eval", str(path), "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    if proc.returncode not in (0, 1):
        raise RuntimeError(f"eval {path} exited {proc.returncode}: {proc.stderr.strip()[-300:]}")
    return wall, cpu


def corpus_rows(root=CORPUS):
    """Timed rows of the corpus sweep (warm) and of one file's eval (warm)."""
    root = Path(root)
    sweep(root)  # warm-up: libraries, numba kernels, texture cache
    c0, t0 = time.process_time(), time.perf_counter()
    records = sweep(root)
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    t = totals(records)
    assert not t["tracebacks"], t["tracebacks"]
    rows_ = [
        {
            "name": f"corpus sweep: {t['files']} files, {t['materials']} materials, CPU time",
            "value": round(cpu, 2),
            "unit": "s",
            "target": None,
            "ok": True,
        },
        {
            "name": f"corpus sweep: {t['files']} files, {t['materials']} materials (load + evaluate)",
            "value": round(wall, 2),
            "unit": "s",
            "target": f"< {CORPUS_TARGET_S:g}",
            "ok": wall < CORPUS_TARGET_S,
        },
    ]
    for rel in EVAL_FILES:
        f = root / rel
        if not f.is_file():
            continue
        _eval_once(f)  # warm-up (numba cache, OS file cache)
        w, c = _eval_once(f)
        rows_ += [
            {
                "name": f"eval {Path(rel).name} --json (subprocess), CPU time",
                "value": round(c, 2),
                "unit": "s",
                "target": None,
                "ok": True,
            },
            {
                "name": f"eval {Path(rel).name} --json (subprocess)",
                "value": round(w, 2),
                "unit": "s",
                "target": f"< {EVAL_TARGET_S:g}",
                "ok": w < EVAL_TARGET_S,
            },
        ]
    return rows_


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="1,000 materials instead of 10,000")
    p.add_argument("--materials", type=int, default=None, help="number of materials")
    p.add_argument("--corpus", action="store_true", help="also time the corpus sweep and one file's eval")
    p.add_argument("--corpus-totals", action="store_true", help="print the corpus sweep's totals (Markdown)")
    p.add_argument("--root", default=str(CORPUS), help="corpus folder (default: the shared real-world corpus)")
    p.add_argument("--write", default=None, help="with --corpus-totals: replace the totals block of this file")
    args = p.parse_args(argv)
    if args.corpus_totals:
        block = totals_markdown(totals(sweep(args.root, evaluate=False)))
        if args.write:
            write_totals(args.write, block)
        print(block)
        return 0
    table = rows(args.quick, args.materials) + (corpus_rows(args.root) if args.corpus else [])
    for r in table:
        print(
            f"{r['name']:72s} {r['value']:>9} {r['unit']}  target {r['target'] or '-':>6}  "
            f"{'ok' if r['ok'] else 'FAIL'}"
        )
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    sys.exit(main())
