"""``openpbr-diffuse colorshift``: spectral vs RGB vs white-then-tint EON albedo of colours.

    openpbr-diffuse colorshift                               # the 24 measured ColorChecker spectra
    openpbr-diffuse colorshift --colors 0.8,0.2,0.1 checker --roughness 1 --mu 0.5 1
    openpbr-diffuse colorshift --colors scene.usda --working-space acescg --json
    openpbr-diffuse colorshift --illuminant A --method "Otsu 2018" --image swatches.png [--force]

COLORS: ``checker`` (the measured 'BabelColor Average' spectra), ``R,G,B`` (working-space
linear RGB in [0, 1], upsampled to a spectrum by --method), or FILE: a ``.csv`` of measured
spectra (wavelength in nm, then one column per spectrum) or a USD / MaterialX file whose
materials' diffuse colours are used.  The quantities are those of
``openpbr_diffuse.spectral.validation``; colour-science does the colorimetry.
"""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..spectral.colorimetry import DEFAULT_ILLUMINANT, DEFAULT_WORKING_SPACE, WORKING_SPACES
from ..spectral.recovery import RECOVERY_METHODS
from ..spectral.validation import DEFAULT_MU, DEFAULT_ROUGHNESS
from ._options import add_command, add_numbers

if TYPE_CHECKING:
    from ..spectral.colorimetry import Colorimetry
    from ..spectral.colorsets import ColourSet

#: accepted spellings of --method (lower case, spaces/dashes/underscores removed) -> method.
METHOD_ALIASES = {"auto": "auto", **{m.lower().replace(" ", ""): m for m in RECOVERY_METHODS}}


#: The command's line in ``openpbr-diffuse --help``.
HELP = "spectral vs RGB colour shift of EON (ColorChecker, RGB colours, material files)"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "colorshift", HELP, run, doc=__doc__)
    p.add_argument(
        "--colors",
        nargs="+",
        default=["checker"],
        metavar="COLOR",
        help="'checker', R,G,B (linear working-space RGB in [0, 1]) or FILE (.csv spectra, "
        ".usd/.usda/.usdc/.usdz/.mtlx materials); default: checker",
    )
    for flag, metavar, what, default in (
        ("--roughness", "R", "EON roughness r in [0, 1]", DEFAULT_ROUGHNESS),
        ("--mu", "MU", "cosine of the view angle in [0, 1]", DEFAULT_MU),
    ):
        add_numbers(
            p, flag, metavar=metavar, default=list(default), help=f"{what} (default {' '.join(map(str, default))})"
        )
    p.add_argument(
        "--method",
        default="auto",
        metavar="METHOD",
        help=f"RGB -> spectrum upsampling: auto (Mallett 2019 for lin_rec709, else Otsu 2018), "
        f"{', '.join(RECOVERY_METHODS)} (spaces optional)",
    )
    p.add_argument(
        "--illuminant",
        default=DEFAULT_ILLUMINANT,
        help="a colour.SDS_ILLUMINANTS name (default D65; e.g. D50, A, FL2, LED-B1)",
    )
    p.add_argument(
        "--working-space",
        default=DEFAULT_WORKING_SPACE,
        metavar="SPACE",
        help=f"RGB working space of the colours and results: {', '.join(WORKING_SPACES)} "
        f"(default lin_rec709; case-insensitive, aliases such as lin_ap1_scene)",
    )
    p.add_argument("--json", action="store_true", help="one JSON document: settings and rows")
    p.add_argument("--image", metavar="PATH", help="write a labelled swatch image (PNG, EXR, ... by suffix)")
    p.add_argument("--force", action="store_true", help="replace the --image PATH if it exists (a regular file)")
    return p


def _usage(message):
    from .main import UsageError

    return UsageError(f"colorshift: {message}")


def _method(name):
    key = name.lower().replace(" ", "").replace("-", "").replace("_", "")
    if key not in METHOD_ALIASES:
        raise _usage(f"--method must be auto or one of {', '.join(RECOVERY_METHODS)}; got {name!r}")
    return METHOD_ALIASES[key]


def _parse_rgb(token):
    parts = token.split(",")
    try:
        rgb = [float(v) for v in parts]
    except ValueError:
        rgb = []
    if len(rgb) != 3:
        raise _usage(f"--colors: {token!r} is not R,G,B (three numbers), 'checker' or an existing file")
    if not all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in rgb):
        raise _usage(f"--colors: {token!r}: R,G,B must be linear working-space values in [0, 1]")
    return rgb


def _file_readers():
    """File suffix -> reader(path, cm, method) -> (ColourSet, warnings)."""
    from ..spectral import colorsets

    readers = {".csv": lambda path, cm, method: (colorsets.from_spectra_csv(path, cm), [])}
    readers.update(
        {
            suffix: lambda path, cm, method: colorsets.from_materials([path], cm, method)
            for suffix in colorsets.MATERIAL_SUFFIXES
        }
    )
    return readers


def colour_set(tokens: Sequence[str], cm: Colorimetry, method: str) -> tuple[ColourSet, list[str]]:
    """The ColourSet (and warnings) the --colors tokens name, in the order given."""
    from pathlib import Path

    from ..spectral import colorsets

    sets: list[ColourSet] = []
    warnings: list[str] = []
    rgbs: list[NDArray[np.float64]] = []
    readers = _file_readers()

    def flush():
        if rgbs:
            sets.append(colorsets.from_rgb(list(rgbs), cm, method))
            rgbs.clear()

    for token in tokens:
        rgb = _parse_rgb(token) if "," in token and not Path(token).is_file() else None
        if rgb is not None:
            rgbs.append(rgb)
            continue
        flush()
        if token == "checker":
            sets.append(colorsets.checker(cm))
            continue
        path = Path(token)
        if not path.is_file():
            raise _usage(f"--colors: {token!r} is not 'checker', R,G,B or an existing file")
        reader = readers.get(path.suffix.lower())
        if reader is None:
            raise _usage(
                f"--colors: {token!r}: files must be .csv (spectra) or "
                f"{'/'.join(colorsets.MATERIAL_SUFFIXES)} (materials)"
            )
        cs, w = reader(path, cm, method)
        sets.append(cs)
        warnings += w
    flush()
    return colorsets.ColourSet.concat(sets), warnings


def _rgb(v):
    return " ".join(f"{x:6.4f}" for x in v)


def _table(result, settings, warnings):
    lines = [
        f"EON colour shift: illuminant {settings['illuminant']}, {settings['observer']}, working space "
        f"{settings['working_space']} ({settings['chromatic_adaptation']}), spectral shape "
        f"{settings['spectral_shape']['start_nm']:g}-{settings['spectral_shape']['end_nm']:g} nm / "
        f"{settings['spectral_shape']['interval_nm']:g} nm, dE = CIEDE2000, Lab white = illuminant white",
        "rgb/spec: albedo_rgb vs albedo_spectral; shift: albedo_spectral vs albedo_white_tint; "
        "dY = relative luminance difference, dC = chroma difference",
    ]
    head = (
        f"{'patch':24} {'r':>5} {'mu':>5}  {'rho_rgb':20}  {'albedo_spectral':20}  {'albedo_rgb':20}  "
        f"{'albedo_white_tint':20}  {'dE rgb/spec':>11} {'dY %':>7} {'dC':>7}  "
        f"{'dE shift':>8} {'dY %':>7} {'dC':>7}"
    )
    lines += [head, "-" * len(head)]
    for row in result.rows():
        flag = "*" if row["rho_rgb_clipped"] else " "
        lines.append(
            f"{row['patch'][:23] + flag:24} {row['roughness']:5.3g} {row['mu']:5.3g}  {_rgb(row['rho_rgb']):20}  "
            f"{_rgb(row['albedo_spectral']):20}  {_rgb(row['albedo_rgb']):20}  {_rgb(row['albedo_white_tint']):20}  "
            f"{row['delta_e_rgb_vs_spectral']:11.4f} {100 * row['rel_luminance_diff_rgb_vs_spectral']:7.3f} "
            f"{row['chroma_diff_rgb_vs_spectral']:7.3f}  {row['delta_e_shift']:8.4f} "
            f"{100 * row['rel_luminance_diff_shift']:7.3f} {row['chroma_diff_shift']:7.3f}"
        )
    if result.rho_rgb_clipped.any():
        lines.append("* colour outside the working-space gamut: albedo_rgb is evaluated on rho_rgb clipped to [0, 1]")
    rt = [(n, d) for n, d in zip(result.colours.names, result.colours.roundtrip_delta_e) if d == d]
    if rt:
        lines.append(
            "upsampling round trip (dE2000, rho_rgb vs colour of the spectrum): "
            + ", ".join(f"{n} {d:.4f}" for n, d in rt)
        )
    r_max = float(result.roughness.max())
    for mu, s in result.summary(r_max).items():
        a, b = s["delta_e_rgb_vs_spectral"], s["delta_e_shift"]
        inside = (
            f", in gamut {a['max_in_gamut'][0]:.4f} ({a['max_in_gamut'][1]})"
            if a["max_in_gamut"][1] not in (None, a["max"][1])
            else ""
        )
        lines.append(
            f"r = {r_max:g}, mu = {mu:g}: dE rgb/spec max {a['max'][0]:.4f} ({a['max'][1]}){inside}, "
            f"median {a['median'][0]:.4f} ({a['median'][1]}); dE shift max {b['max'][0]:.4f} "
            f"({b['max'][1]}), median {b['median'][0]:.4f} ({b['median'][1]})"
        )
    lines += [f"warning: {w}" for w in warnings]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from ..spectral.colorimetry import colorimetry
    from ..spectral.validation import colour_shift

    method = _method(args.method)
    image_inputs = [c for c in args.colors if os.path.isfile(c)]
    if args.image:
        from .._outfile import check_output_file

        check_output_file(args.image, option="--image", force=args.force, inputs=image_inputs)  # before any work
    elif args.force:
        raise _usage("--force applies to --image PATH only")
    try:
        cm = colorimetry(args.illuminant, args.working_space)
    except ImportError as exc:  # colour-science missing: one line, exit 2
        raise _usage(str(exc)) from None
    colours, warnings = colour_set(args.colors, cm, method)
    result = colour_shift(colours, args.roughness, args.mu, cm)
    settings = result.settings()
    from ..spectral.recovery import resolve_method

    settings["method"] = method
    settings["method_resolved"] = resolve_method(method, cm)
    settings["colors"] = list(args.colors)
    rt = colours.roundtrip_delta_e[~np.isnan(colours.roundtrip_delta_e)]
    settings["roundtrip_delta_e_max"] = float(rt.max()) if rt.size else None  # over the upsampled colours
    image = None
    if args.image:
        from ..spectral.swatches import write_swatches

        image = str(write_swatches(result, args.image, force=args.force, inputs=image_inputs))
    if args.json:
        doc = {"settings": settings, "rows": result.rows(), "warnings": warnings, "image": image}
        print(json.dumps(doc))
    else:
        print(_table(result, settings, warnings))
        if image:
            print(f"image: {image}")
    return 0
