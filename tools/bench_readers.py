"""Benchmark of the material readers: resolve and evaluate a generated stage of N materials.

    python tools/bench_readers.py [--quick] [--materials N]

The stage (written with the Sdf API into a temporary .usdc, not timed) holds N materials:
70 % OpenPBR (half of them with base_color and roughness through Material interface inputs),
20 % UsdPreviewSurface, 10 % Standard Surface, with random colours and roughness (seeded).
Timed (wall clock, and the process's CPU time, which a busy machine inflates less):
``load_materials`` (open, resolve every input with provenance, map onto the library
node) and ``evaluate_many`` (BRDF, albedo, diffuse weight and probability of every material
at one direction pair, vectorised per node group).  Target: < 10 s for 10,000 materials.
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

TARGET_S = 10.0


def make_stage(path, n, seed=10):
    """Write a stage with ``n`` materials to ``path`` (a .usdc)."""
    from pxr import Sdf, Usd, UsdShade

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
            sid = ("ND_open_pbr_surface_surfaceshader", "UsdPreviewSurface", "ND_standard_surface_surfaceshader")[kinds[i]]
            Sdf.AttributeSpec(sh, "info:id", Sdf.ValueTypeNames.Token, variability=Sdf.VariabilityUniform).default = sid
            out_name = "outputs:surface" if kinds[i] == 1 else "outputs:out"
            Sdf.AttributeSpec(sh, out_name, Sdf.ValueTypeNames.Token)
            surf = Sdf.AttributeSpec(mat, "outputs:surface" if kinds[i] == 1 else "outputs:mtlx:surface",
                                     Sdf.ValueTypeNames.Token)
            surf.connectionPathList.explicitItems = [Sdf.Path(f"{mpath}/S.{out_name}")]
            colour = tuple(float(x) for x in colours[i])
            names = {0: ("base_color", "base_diffuse_roughness", "specular_roughness"),
                     1: ("diffuseColor", None, "roughness"),
                     2: ("base_color", "diffuse_roughness", "specular_roughness")}[kinds[i]]
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
        {"name": f"readers: resolve + evaluate {n} materials, CPU time of the process", "value": round(cpu, 3),
         "unit": "s", "target": None, "ok": True},
        {"name": f"readers: resolve {n} USD materials", "value": round(t_resolve, 3), "unit": "s",
         "target": None, "ok": True},
        {"name": f"readers: evaluate {n} materials (evaluate_many)", "value": round(t_eval, 3), "unit": "s",
         "target": None, "ok": True},
        {"name": f"readers: resolve + evaluate {n} materials", "value": round(total, 3), "unit": "s",
         "target": f"< {target:g}", "ok": total < target},
    ]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="1,000 materials instead of 10,000")
    p.add_argument("--materials", type=int, default=None, help="number of materials")
    args = p.parse_args(argv)
    for r in rows(args.quick, args.materials):
        print(f"{r['name']:55s} {r['value']:>9} {r['unit']}  target {r['target'] or '-':>6}  "
              f"{'ok' if r['ok'] else 'FAIL'}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    sys.exit(main())
