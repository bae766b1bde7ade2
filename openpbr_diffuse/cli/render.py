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


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "render",
        help="preview a material on a sphere (directional and furnace light)",
        description=__doc__.splitlines()[0].strip("`").replace("``", ""),
    )
    add_material_options(p)
    p.add_argument("--out", required=True, metavar="IMAGE", help="output image (.exr linear, .png sRGB)")
    p.add_argument("--force", action="store_true", help="replace IMAGE if it exists (a regular file)")
    p.add_argument("--size", type=int, default=256, metavar="N", help="height of the image in pixels (default 256)")
    p.set_defaults(run=run)
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
