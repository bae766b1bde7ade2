"""``openpbr-diffuse eval``: what diffuse lobe a USD / MaterialX material really describes.

    openpbr-diffuse eval materials/clay_rough.mtlx
    openpbr-diffuse eval scene.usda --material /World/Ball --theta-i 0 30 60 --theta-o 45 --phi 180
    openpbr-diffuse eval paint.usda --variant finish=gloss --time 12 --uv 0.25 0.75 --json
    openpbr-diffuse eval LIBRARY_DIR more.usda --jsonl materials.jsonl   # many files: one line per material

For each material (or the one asked for, or the material bound to a geometry prim): the
resolved parameters with their provenance (colours in ACEScg), the diffuse lobe's effective
weight and selection probability, the directional albedo at theta_o and the BRDF values
(no cosine) at the given directions.  Angles in degrees; phi is the azimuth of wi relative
to wo (180: forward, in the plane of incidence).

``--jsonl OUT`` (batch mode): any number of files and folders (searched recursively), one JSON
line per material written as the files are done, in the order of the files (each line as an
entry of ``--json``'s "materials", plus "relpath" and "index"; a file that cannot be read is one
line with "error" and "path": null).  The files are read by worker processes (``--jobs``),
results are kept in the cache (``--cache-dir`` / ``--no-cache``) or the work goes to a Dask
cluster (``--scheduler``), as for ``report``.  OUT follows the rule of every output file: an
existing file is replaced only with ``--force``; ``-`` writes to stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from ._library import add_library_options
from ._materials import FILE_HELP, add_material_options, load
from ._options import add_command, add_numbers

#: The direction options (degrees): flag, default, help.
_DIRECTION_OPTIONS = (
    ("--theta-i", 30.0, "incidence angle(s) of wi from the normal, degrees in [0, 90] (default 30)"),
    ("--theta-o", 30.0, "view angle(s) of wo, degrees in [0, 90] (default 30)"),
    ("--phi", 180.0, "azimuth of wi relative to wo, degrees (default 180)"),
)


#: The command's line in ``openpbr-diffuse --help``.
HELP = "evaluate the materials of a USD / MaterialX file"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "eval", HELP, run, doc=__doc__)
    # with --jsonl the FILE may be a folder, and more may follow
    add_material_options(p, file_help=FILE_HELP + "; with --jsonl also folders")
    p.add_argument("more", nargs="*", metavar="FILE", help="more files or folders (with --jsonl)")
    for flag, default, help in _DIRECTION_OPTIONS:
        add_numbers(p, flag, metavar="DEG", default=[default], help=help)
    p.add_argument("--all", action="store_true", help="list every parameter, not only the set and modelled ones")
    p.add_argument("--json", action="store_true", help="one JSON document (schema in the README)")
    p.add_argument(
        "--jsonl",
        metavar="OUT",
        default=None,
        help="batch mode: one JSON line per material of every FILE and folder, written as they are done (- for stdout)",
    )
    p.add_argument("--force", action="store_true", help="replace the --jsonl OUT file if it exists")
    p.add_argument("--no-progress", action="store_true", help="no progress bar or lines (--jsonl)")
    add_library_options(p)
    return p


def _safe(text: str) -> str:
    """Text from a user's file with control characters escaped repr-style (``\\x1b``)."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def _fmt(v):
    if isinstance(v, (tuple, list)):
        return "(" + ", ".join(_fmt(x) for x in v) + ")"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _rgb(a):
    return "(" + ", ".join(f"{x:.6f}" for x in a) + ")"


def _node_defaults(node_class):
    from ..readers import mxlib

    nd = {
        "OpenPBRSurface": "ND_open_pbr_surface_surfaceshader",
        "OrenNayarDiffuseBSDF": "ND_oren_nayar_diffuse_bsdf",
    }.get(node_class)
    return {n: v for n, (t, v, g) in mxlib.inputs(nd).items()} if nd else {}


def run(args: argparse.Namespace) -> int:
    from ..readers import WORKING_SPACE
    from ..readers.evaluate import evaluate

    try:
        ti, to, ph = np.broadcast_arrays(np.asarray(args.theta_i), np.asarray(args.theta_o), np.asarray(args.phi))
    except ValueError:
        raise ValueError("eval: --theta-i, --theta-o and --phi must have the same number of values (or one)") from None
    if args.jsonl is not None:
        from .eval_batch import run_jsonl

        return run_jsonl(args, ti, to, ph)
    if args.force:
        raise ValueError("eval: --force applies to --jsonl OUT only")
    if os.path.isdir(args.file):
        raise ValueError(f"eval: {args.file} is a directory: a folder needs --jsonl OUT (one JSON line per material)")
    if args.more:
        raise ValueError("eval: several files need --jsonl OUT (one JSON line per material)")
    materials = load(args)
    results = [(m, evaluate(m, ti, to, ph)) for m in materials]
    # 0: every material read (unsupported shaders listed as such); 1: some could not be
    # evaluated (each named with its reason); 2 (raised before): the file itself is unusable
    status = 1 if any(m.error for m in materials) else 0
    if args.json:
        doc = {
            "file": args.file,
            "working_space": WORKING_SPACE,
            "time": args.time,
            "variants": dict(v.split("=", 1) for v in args.variant),
            "uv": list(args.uv),
            "directions": {
                "theta_i": ti.tolist(),
                "theta_o": to.tolist(),
                "phi": ph.tolist(),
                "units": "degrees",
                "frame": "local, normal +z; phi = azimuth of wi relative to wo",
            },
            "materials": [dict(m.to_dict(), evaluation=r) for m, r in results],
        }
        print(json.dumps(doc, allow_nan=False))
        _name_failed(materials)
        return status
    for m, r in results:
        if m.error:
            print(f"# {_safe(m.path)}  [not evaluated]  from {_safe(m.file)}")
            print(f"  error: {_safe(m.error)}")
            continue
        print(f"# {_safe(m.path)}  [{_safe(m.shader_id) or 'no shader'}]  from {_safe(m.file)}")
        if not m.supported:
            print("  not supported: " + _safe("; ".join(m.unsupported)))
            for w in m.warnings:
                print(f"  warning: {_safe(w)}")
            continue
        print(
            f"  node: {m.node_class}"
            + (f" (diffuse {m.diffuse_model})" if m.diffuse_model else "")
            + f"; colours in {WORKING_SPACE}"
        )
        print("  parameters:")
        for name, p in m.parameters.items():
            if (
                not args.all
                and p.kind == "default"
                and name
                not in (
                    "base_color",
                    "base_diffuse_roughness",
                    "base_weight",
                    "color",
                    "roughness",
                    "weight",
                    "diffuseColor",
                )
            ):
                continue
            print(f"    {name} = {_fmt(p.value)}    <- {p.provenance}")
        # node inputs that differ from the shader's own (mapped from another shader, or
        # clamped); without --all, mapped values equal to the node's defaults are not shown
        shown = False
        node_defaults = _node_defaults(m.node_class)
        for name, p in m.node_inputs.items():
            own = m.parameters.get(name)
            if not args.all and (
                p.kind == "default"
                or (own is not None and own.value == p.value)
                or (own is None and node_defaults.get(name) == p.value)
            ):
                continue
            if not shown:
                print(f"  {m.node_class} inputs (mapped / clamped):")
                shown = True
            print(f"    {name} = {_fmt(p.value)}    <- {p.provenance}")
        n = len(r["theta_o"])
        d = r["diffuse"]
        # one line per distinct theta_o (these depend on wo only)
        first = sorted({r["theta_o"][k]: k for k in reversed(range(n))}.values())
        print("  diffuse lobe (weight, selection probability, albedo of the lobe, weight x albedo):")
        for k in first:
            print(
                f"    theta_o {r['theta_o'][k]:g}: weight {_rgb(d['weight'][k])}  P {d['probability'][k]:.6f}  "
                f"E {_rgb(d['albedo'][k])}  w*E {_rgb(d['contribution'][k])}"
            )
        print("  directional albedo of the material:")
        for k in first:
            print(f"    theta_o {r['theta_o'][k]:g}: {_rgb(r['albedo'][k])}")
        print("  BRDF f(wi, wo) (no cosine):")
        for k in range(n):
            print(
                f"    theta_i {r['theta_i'][k]:g} theta_o {r['theta_o'][k]:g} phi {r['phi'][k]:g}: {_rgb(r['brdf'][k])}"
            )
        for u in m.unsupported:
            print(f"  unsupported: {_safe(u)}")
        for a in m.approximations:
            print(f"  approximation: {a}")
        for w in m.warnings:
            print(f"  warning: {_safe(w)}")
    _name_failed(materials)
    return status


def _name_failed(materials: list) -> None:
    """One line on stderr naming the materials that could not be evaluated (exit status 1)."""
    bad = [m for m in materials if m.error]
    if bad:
        print(
            f"{len(bad)} of {len(materials)} material(s) could not be evaluated: "
            + ", ".join(_safe(m.path) for m in bad),
            file=sys.stderr,
        )


__all__ = ["add_parser", "run"]
