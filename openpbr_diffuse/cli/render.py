"""``openpbr-diffuse render``: a preview of a material on a sphere, written with OpenImageIO.

    openpbr-diffuse render materials/clay_rough.mtlx --out clay.png
    openpbr-diffuse render scene.usda --material /World/Ball --out ball.exr --size 256

An existing IMAGE is replaced only with ``--force``.

Left: the sphere under a directional light; right: under a uniform white environment (the
furnace: each pixel is the directional albedo at its view angle).  EXR: linear ACEScg, float;
PNG: sRGB, 8 bit (see :mod:`openpbr_diffuse.readers.preview`).
"""

from __future__ import annotations

import argparse
import os

from .._outfile import check_output_file
from ..readers.preview import render_image, write_image
from ._materials import add_material_options, load
from ._options import add_command, add_output

#: The command's line in ``openpbr-diffuse --help``.
HELP = "preview a material on a sphere (directional and furnace light)"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "render", HELP, run, doc=__doc__)
    add_material_options(p)
    add_output(
        p,
        "output image (.exr linear, .png sRGB)",
        metavar="IMAGE",
        force_help="replace IMAGE if it exists (a regular file)",
    )
    p.add_argument("--size", type=int, default=256, metavar="N", help="height of the image in pixels (default 256)")
    return p


def _check_out(path):
    if os.path.splitext(path)[1].lower() not in (".exr", ".png", ".jpg", ".jpeg", ".tif", ".tiff"):
        raise ValueError(f"--out must end in .exr or .png (also .jpg, .tif), got {path!r}")


def run(args: argparse.Namespace) -> int:
    _check_out(args.out)
    if not 8 <= args.size <= 4096:
        raise ValueError(f"size must be an integer in [8, 4096], got {args.size!r}")
    out = {"force": args.force, "inputs": [args.file]}
    check_output_file(args.out, option="--out", **out)  # before any work
    materials = load(args)
    if len(materials) != 1:
        names = ", ".join(m.path for m in materials[:8])
        raise ValueError(f"render: {len(materials)} materials in {args.file} ({names}); choose one with --material")
    if materials[0].error:
        raise ValueError(f"render: {materials[0].path} cannot be evaluated: {materials[0].error}")
    img = render_image(materials[0], args.size)
    write_image(img, args.out, **out)
    print(args.out)
    return 0


__all__ = ["add_parser", "run"]
