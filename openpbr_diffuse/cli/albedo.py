"""``openpbr-diffuse albedo``: the lobe-albedo query and the real-time LUT export.

    openpbr-diffuse albedo eon --roughness 1 --mu 0.3 0.8 --rho 0.8 0.5 0.2
    openpbr-diffuse albedo full_on --roughness 0.5 --mu 0.05 --reference
    openpbr-diffuse albedo qon --roughness 0.7854 --average --json
    openpbr-diffuse albedo eon --export luts/ --size 64

Values come from ``directional_albedo`` / ``average_albedo`` (closed forms; the reference
tables for "full_on").  ``--reference`` adds an independent value and the difference: the
reference-table value for closed-form models, and for "full_on" (whose value already is the
table's) a direct quadrature of ``evaluate``.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from ..models import average_albedo, directional_albedo
from ..models.registry import COLOR_MODES, MIX_RHO_MS, MODELS, model_info
from ._options import add_command, add_number, add_numbers

#: The command's line in ``openpbr-diffuse --help``.
HELP = "directional / average albedo of a lobe model; EXR LUT export"
DESCRIPTION = "Directional or average albedo of a lobe model, or its EXR lookup textures (--export)."
EPILOG = """examples:
  openpbr-diffuse albedo eon --roughness 1 --mu 0.3 0.8 --rho 0.8 0.5 0.2
  openpbr-diffuse albedo full_on --roughness 0.5 --mu 0.05 --reference
  openpbr-diffuse albedo qon --roughness 0.7854 --average --json
  openpbr-diffuse albedo eon --export luts/ --size 64"""

#: Options of the query that ``--export`` (whole tables) cannot take.
_QUERY_OPTIONS = (
    ("roughness", "--roughness"),
    ("mu", "--mu"),
    ("rho", "--rho"),
    ("color_mode", "--color-mode"),
    ("average", "--average"),
    ("reference", "--reference"),
)


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    import argparse

    p = add_command(
        subparsers,
        "albedo",
        HELP,
        run,
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("model", metavar="MODEL", help=f"lobe model: {', '.join(MODELS)}")
    add_number(
        p,
        "--roughness",
        metavar="R",
        help="sigma in radians [0, pi/2] (qon*, full_on, gotanda) or r in [0, 1] (fon, eon*); lambert has none",
    )
    add_numbers(p, "--mu", metavar="MU", help="cosine(s) of the view angle in [0, 1]")
    add_numbers(p, "--rho", metavar="RHO", help="albedo per channel in [0, 1] (1, 3 or N values; default 1)")
    p.add_argument(
        "--color-mode",
        choices=COLOR_MODES,
        default=None,
        help="EON models only: 'reference' (default) or 'white_tint' = rho * E(rho = 1)",
    )
    p.add_argument("--average", action="store_true", help="average albedo <E> = 2 int E mu dmu instead of E(mu)")
    p.add_argument(
        "--reference",
        action="store_true",
        help="also show an independent value (reference table, or quadrature for full_on) and the difference",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--export", metavar="DIR", help="write EXR lookup textures of E(mu, roughness) and <E>(roughness) to DIR"
    )
    p.add_argument("--size", type=int, default=None, metavar="N", help="texture size for --export (default 32)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr during --export")
    p.add_argument("--force", action="store_true", help="replace the --export files if they exist (regular files)")
    return p


def _usage(message):
    from .main import UsageError

    return UsageError(message, prog="openpbr-diffuse albedo")


def _export(args, info):
    from ..albedo.export import DEFAULT_SIZE, export_lut

    given = [flag for key, flag in _QUERY_OPTIONS if getattr(args, key) not in (None, False)]
    if given:
        raise _usage(f"--export writes whole tables over mu and roughness at rho = 1; it takes no {', '.join(given)}")
    paths = export_lut(
        info.name,
        args.export,
        DEFAULT_SIZE if args.size is None else args.size,
        progress=False if args.no_progress else None,
        force=args.force,
    )
    if args.json:
        print(json.dumps({"model": info.name, "files": list(paths)}))
    else:
        for path in paths:
            print(path)
    return 0


def _fmt(v):
    return f"{v:.8f}"


def _quadrature_reference(name, mu, roughness, rho, average):
    """E (or <E>) by direct quadrature of ``evaluate``, with its error estimate (full_on)."""
    from ..albedo.quadrature import hemisphere_albedo, hemisphere_average_albedo
    from ..models.api import evaluate

    def brdf(wi, wo):
        return evaluate(name, wi, wo, roughness, rho)

    if average:
        value, err = hemisphere_average_albedo(brdf, error=True)
        return value[None], float(np.max(err))
    value, err = hemisphere_albedo(brdf, mu, error=True)
    return value, float(np.max(err))


def run(args: argparse.Namespace) -> int:
    info = model_info(args.model)
    if args.export is not None:
        return _export(args, info)
    if args.size is not None:
        raise _usage("--size only applies with --export")
    if args.no_progress:
        raise _usage("--no-progress only applies with --export")
    if args.force:
        raise _usage("--force only applies with --export")
    if info.name == "lambert":
        if args.roughness is not None:
            raise _usage("lambert has no roughness (f = rho/pi); omit --roughness")
        roughness = 0.0
    elif args.roughness is None:
        raise _usage("--roughness is required")
    else:
        roughness = args.roughness
    color_mode = "reference" if args.color_mode is None else args.color_mode
    if color_mode != "reference" and info.mix != MIX_RHO_MS:
        raise _usage(f"--color-mode {color_mode} applies to the EON models only (eon, eon_approx), not {info.name}")
    if args.average and args.mu:
        raise _usage("--average takes no --mu")
    if not args.average and not args.mu:
        raise _usage("--mu is required (or --average)")
    rho = np.array([1.0] if args.rho is None else args.rho, dtype=np.float64)
    mu = None
    if args.average:
        value = average_albedo(info.name, roughness, rho, color_mode=color_mode)[None]
    else:
        mu = np.array(args.mu, dtype=np.float64)
        value = directional_albedo(info.name, mu, roughness, rho, color_mode=color_mode)
    ref = None
    if args.reference:
        if info.closed_form_albedo:
            from ..albedo.tables import load_table, reference_albedo, reference_average_albedo

            ref_source = "reference table"
            ref_error = load_table(info.name).interpolation_error
            if args.average:
                ref = reference_average_albedo(info.name, roughness, rho, color_mode=color_mode)[None]
            else:
                ref = reference_albedo(info.name, mu, roughness, rho, color_mode=color_mode)  # type: ignore[arg-type]
        else:  # the value is the table's: compare with the integral it was made from
            ref_source = "quadrature of evaluate"
            ref, ref_error = _quadrature_reference(info.name, mu, roughness, rho, args.average)
    source = "closed form" if info.closed_form_albedo else "reference table"
    rough_key = None if info.name == "lambert" else info.roughness_name
    if args.json:
        out: dict[str, object] = {"model": info.name}
        if rough_key:
            out[rough_key] = roughness
        out.update({"rho": rho.tolist(), "color_mode": color_mode, "source": source})
        if args.average:
            out["average_albedo"] = value[0].tolist()
        else:
            out["mu"] = mu.tolist()  # type: ignore[union-attr]  # set unless --average
            out["albedo"] = value.tolist()
        if ref is not None:
            key = "reference_average_albedo" if args.average else "reference_albedo"
            out[key] = ref[0].tolist() if args.average else ref.tolist()
            out["difference"] = (value - ref)[0].tolist() if args.average else (value - ref).tolist()
            out["reference_source"] = ref_source
            out["reference_error"] = ref_error
        print(json.dumps(out))
        return 0
    C = rho.size
    chan = [""] if C == 1 else [f"[{k}]" for k in range(C)]
    rough_text = f", {rough_key} = {roughness!r}" if rough_key else " (no roughness)"
    print(
        f"# model {info.name}{rough_text}, rho = ({', '.join(repr(float(r)) for r in rho)}), "
        f"color mode {color_mode}, {source}"
        + (f"; reference: {ref_source}, accurate to {ref_error:.2g}" if ref is not None else "")
    )
    cols = [] if args.average else ["mu"]
    for c in chan:
        cols += ["<E>" + c if args.average else "E" + c]
        if ref is not None:
            cols += ["ref" + c, "diff" + c]
    widths = [max(10, len(c)) for c in cols]
    print("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
    for i in range(value.shape[0]):
        cells = [] if args.average else [f"{mu[i]:.6f}"]  # type: ignore[index]  # set unless --average
        for k in range(C):
            cells.append(_fmt(value[i, k]))
            if ref is not None:
                cells += [_fmt(ref[i, k]), f"{value[i, k] - ref[i, k]:+.1e}"]
        print("  ".join(c.rjust(w) for c, w in zip(cells, widths)))
    return 0


__all__ = ["add_parser", "run"]
