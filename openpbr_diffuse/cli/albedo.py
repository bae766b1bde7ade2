"""``openpbr-diffuse albedo``: the lobe-albedo query and the real-time LUT export.

    openpbr-diffuse albedo eon --roughness 1 --mu 0.3 0.8 --rho 0.8 0.5 0.2
    openpbr-diffuse albedo full_on --roughness 0.5 --mu 0.05 --reference
    openpbr-diffuse albedo qon --roughness 0.7854 --average --json
    openpbr-diffuse albedo eon --export luts/ --size 64

Values come from ``directional_albedo`` / ``average_albedo`` (closed forms; the reference
tables for "full_on"); ``--reference`` adds the reference-table value and the difference.
"""
import json

import numpy as np

from ..models import average_albedo, directional_albedo
from ..models.registry import COLOR_MODES, MODELS, model_info


def add_parser(subparsers):
    p = subparsers.add_parser(
        "albedo", help="directional / average albedo of a lobe model; EXR LUT export",
        description=__doc__.splitlines()[0].strip("`").replace("``", ""))
    p.add_argument("model", metavar="MODEL", help=f"lobe model: {', '.join(MODELS)}")
    p.add_argument("--roughness", type=float, metavar="R",
                   help="sigma in radians [0, pi/2] (qon*, full_on, gotanda) or r in [0, 1] (fon, eon*)")
    p.add_argument("--mu", type=float, nargs="+", metavar="MU", help="cosine(s) of the view angle in [0, 1]")
    p.add_argument("--rho", type=float, nargs="+", metavar="RHO", default=[1.0],
                   help="albedo per channel in [0, 1] (1, 3 or N values; default 1)")
    p.add_argument("--color-mode", choices=COLOR_MODES, default="reference",
                   help="'white_tint': rho * E(rho = 1) (no colour shift)")
    p.add_argument("--average", action="store_true", help="average albedo <E> = 2 int E mu dmu instead of E(mu)")
    p.add_argument("--reference", action="store_true",
                   help="also show the reference-table value and the difference")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--export", metavar="DIR", help="write EXR lookup textures of E(mu, roughness) and <E>(roughness)")
    p.add_argument("--size", type=int, default=None, metavar="N", help="texture size for --export (default 32)")
    p.set_defaults(run=run)
    return p


def _usage(message):
    from .main import UsageError

    return UsageError(f"albedo: {message}")


def _export(args, info):
    from ..albedo.export import DEFAULT_SIZE, export_lut

    paths = export_lut(info.name, args.export, DEFAULT_SIZE if args.size is None else args.size)
    if args.json:
        print(json.dumps({"model": info.name, "files": list(paths)}))
    else:
        for path in paths:
            print(path)
    return 0


def _fmt(v):
    return f"{v:.8f}"


def run(args):
    info = model_info(args.model)
    if args.export is not None:
        return _export(args, info)
    if args.size is not None:
        raise _usage("--size only applies with --export")
    if args.roughness is None:
        if info.name != "lambert":
            raise _usage("--roughness is required")
        args.roughness = 0.0
    if args.average and args.mu:
        raise _usage("--average takes no --mu")
    if not args.average and not args.mu:
        raise _usage("--mu is required (or --average)")
    rho = np.array(args.rho, dtype=np.float64)
    if args.average:
        value = average_albedo(info.name, args.roughness, rho, color_mode=args.color_mode)[None]
    else:
        mu = np.array(args.mu, dtype=np.float64)
        value = directional_albedo(info.name, mu, args.roughness, rho, color_mode=args.color_mode)
    ref = table = None
    if args.reference:
        from ..albedo.tables import load_table, reference_albedo, reference_average_albedo

        table = load_table(info.name)
        if args.average:
            ref = reference_average_albedo(info.name, args.roughness, rho, color_mode=args.color_mode)[None]
        else:
            ref = reference_albedo(info.name, mu, args.roughness, rho, color_mode=args.color_mode)
    source = "closed form" if info.closed_form_albedo else "reference table"
    if args.json:
        out = {"model": info.name, info.roughness_name: args.roughness, "rho": rho.tolist(),
               "color_mode": args.color_mode, "source": source}
        if args.average:
            out["average_albedo"] = value[0].tolist()
        else:
            out["mu"] = mu.tolist()
            out["albedo"] = value.tolist()
        if ref is not None:
            key = "reference_average_albedo" if args.average else "reference_albedo"
            out[key] = ref[0].tolist() if args.average else ref.tolist()
            out["difference"] = (value - ref)[0].tolist() if args.average else (value - ref).tolist()
            out["reference_error"] = table.interpolation_error
        print(json.dumps(out))
        return 0
    C = rho.size
    chan = [""] if C == 1 else [f"[{k}]" for k in range(C)]
    print(f"# model {info.name}, {info.roughness_name} = {args.roughness:g}, rho = "
          f"({', '.join(f'{r:g}' for r in rho)}), color mode {args.color_mode}, {source}"
          + (f"; reference tables accurate to {table.interpolation_error:.0e}" if table else ""))
    cols = [] if args.average else ["mu"]
    for c in chan:
        cols += ["<E>" + c if args.average else "E" + c]
        if ref is not None:
            cols += ["ref" + c, "diff" + c]
    widths = [max(10, len(c)) for c in cols]
    print("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
    for i in range(value.shape[0]):
        cells = [] if args.average else [f"{mu[i]:.6f}"]
        for k in range(C):
            cells.append(_fmt(value[i, k]))
            if ref is not None:
                cells += [_fmt(ref[i, k]), f"{value[i, k] - ref[i, k]:+.1e}"]
        print("  ".join(c.rjust(w) for c, w in zip(cells, widths)))
    return 0


__all__ = ["add_parser", "run"]
