"""``openpbr-diffuse simulate --layered``: Monte Carlo albedo of a diffuse base under a dielectric layer.

    openpbr-diffuse simulate --layered --interface smooth --ior 1.5 --base lambert --rho 0.8 --mu 1 0.5 0.1
    openpbr-diffuse simulate --layered --interface ggx --ior 1.5 --interface-roughness 0.25 \\
        --coat-color 0.9 0.6 0.3 --base eon --roughness 0.5 --rho 0.8 --mu 0.5 --json

Prints, per mu, the directional albedo split into the specular part (first-interface
reflection), the diffuse part (light that reached the base) and the total, each with its
standard error (``--json``: the same numbers, ``LayeredAlbedo.to_dict``).
"""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING

import numpy as np

from ._options import add_number, add_numbers

if TYPE_CHECKING:
    from .main import UsageError

BASES = ("lambert", "eon", "smith-ggx", "vcavity")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the ``--layered`` options to the ``simulate`` parser."""
    g = p.add_argument_group("layered surface (--layered)")
    g.add_argument(
        "--layered",
        action="store_true",
        help="simulate a dielectric interface over an absorbing slab over a diffuse base",
    )
    g.add_argument("--interface", choices=("smooth", "ggx"), default="smooth", help="interface (default smooth)")
    add_number(g, "--ior", metavar="N", help="relative index of refraction of the layer, [1, 4]")
    add_number(
        g,
        "--interface-roughness",
        default=0.0,
        metavar="A",
        help="GGX width alpha of the interface in [0, 1] (OpenPBR: coat_roughness^2)",
    )
    add_numbers(g, "--absorption", metavar="A", help="absorption coefficient(s), with --thickness")
    add_number(g, "--thickness", metavar="D", help="slab thickness, with --absorption")
    add_numbers(
        g,
        "--coat-color",
        metavar="C",
        help="transmittance of one pass at normal incidence (OpenPBR coat_color), per channel",
    )
    g.add_argument(
        "--base",
        choices=BASES,
        default="lambert",
        help="diffuse base (default lambert; smith-ggx: simulated Smith GGX Lambertian microsurface, "
        "--roughness its alpha)",
    )


def _usage(message: str) -> UsageError:
    from .main import UsageError

    return UsageError(f"simulate: {message}")


def run(args: argparse.Namespace) -> int:
    """Run ``simulate --layered``; prints the table (or JSON) and returns 0."""
    from ..simulation.layered import (
        LayeredSurface,
        simulate_layered_albedo,
        simulate_layered_average_albedo,
    )

    if args.ior is None:
        raise _usage("--layered needs --ior")
    if args.geometry is not None:
        raise _usage("--layered takes --base, not --geometry")
    if args.base == "vcavity":
        raise _usage("--base vcavity is not available for --layered (use lambert, eon or smith-ggx)")
    if (args.absorption is None) != (args.thickness is None):
        raise _usage("--absorption and --thickness go together")
    if args.coat_color is not None and args.absorption is not None:
        raise _usage("give --coat-color or --absorption/--thickness, not both")
    if args.interface == "smooth" and args.interface_roughness:
        raise _usage("--interface-roughness needs --interface ggx")
    if args.average and args.mu:
        raise _usage("--average takes no --mu")
    if not args.average and not args.mu:
        raise _usage("--mu is required (or --average)")
    roughness = 0.0 if args.roughness is None else args.roughness
    if args.base == "lambert" and roughness:
        raise _usage("--roughness is the EON base roughness: needs --base eon")
    kw = {}
    if args.absorption is not None:
        kw = {"absorption": np.array(args.absorption), "thickness": args.thickness}
    elif args.coat_color is not None:
        kw = {"coat_color": np.array(args.coat_color)}
    surface = LayeredSurface(
        args.interface, args.ior, args.interface_roughness, base=args.base, roughness=roughness, **kw
    )
    rho = np.array(args.rho, dtype=np.float64)
    run_kw = {"rho": rho, "paths": args.paths, "seed": args.seed, "workers": args.workers, "scheduler": args.scheduler}
    try:
        if args.average:
            est = simulate_layered_average_albedo(surface, **run_kw)
        else:
            est = simulate_layered_albedo(surface, np.array(args.mu, dtype=np.float64), **run_kw)
    except ImportError as exc:
        raise _usage(str(exc)) from None
    if args.json:
        print(json.dumps(est.to_dict()))
        return 0
    C = est.total.shape[1]
    chan = [""] if C == 1 else [f"[{k}]" for k in range(C)]
    slab = (
        "coat_color = (" + ", ".join(f"{c:g}" for c in args.coat_color) + ")"
        if args.coat_color is not None
        else f"tau = ({', '.join(f'{t:g}' for t in surface.tau)})"
    )
    print(
        f"# {args.interface} interface, ior {surface.ior:g}"
        + (f", alpha {surface.interface_alpha:g}" if args.interface == "ggx" else "")
        + f", {slab}, base {args.base}"
        + (f" roughness {roughness:g}" if args.base != "lambert" else "")
        + f", rho = ({', '.join(f'{r:g}' for r in est.rho)}), {args.paths} paths per row, seed {args.seed};"
        " values +- one standard error"
    )
    cols = ["mu"]
    for c in chan:
        cols += ["specular" + c, "diffuse" + c, "total" + c]
    widths = [8] + [21] * (len(cols) - 1)
    print("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
    for i in range(est.total.shape[0]):
        cells = ["average" if est.mu is None else f"{est.mu[i]:.6f}"]
        for k in range(C):
            cells += [
                f"{est.specular[i, k]:.6f} +- {est.specular_stderr[i, k]:.1e}",
                f"{est.diffuse[i, k]:.6f} +- {est.diffuse_stderr[i, k]:.1e}",
                f"{est.total[i, k]:.6f} +- {est.total_stderr[i, k]:.1e}",
            ]
        print("  ".join(c.rjust(w) for c, w in zip(cells, widths)))
    return 0


__all__ = ["add_arguments", "run"]
