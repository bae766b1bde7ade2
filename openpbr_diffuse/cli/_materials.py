"""Options shared by the material sub-commands (eval, render): file, material, time, uv,
variants, purpose."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..readers.material import Material


#: What the FILE argument reads.
FILE_HELP = "USD stage (.usda/.usdc/.usdz) or MaterialX document (.mtlx)"


def add_material_options(
    p: argparse.ArgumentParser, material_required: bool = False, file_help: str = FILE_HELP
) -> None:
    """FILE, ``--material``, ``--uv``, ``--time``, ``--variant`` and ``--purpose``."""
    p.add_argument("file", metavar="FILE", help=file_help)
    p.add_argument(
        "--material",
        metavar="PRIM_OR_NAME",
        required=material_required,
        help="material prim path or name (MaterialX: node name), or a geometry prim: its bound material",
    )
    p.add_argument(
        "--uv",
        type=float,
        nargs=2,
        metavar=("U", "V"),
        default=(0.5, 0.5),
        help="texture coordinates where textures are sampled (default 0.5 0.5; v up)",
    )
    p.add_argument("--time", type=_time_code, metavar="T", default=None, help="USD time code for time-sampled inputs")
    p.add_argument(
        "--variant", action="append", metavar="SET=VALUE", default=[], help="USD variant selection (repeatable)"
    )
    p.add_argument(
        "--purpose",
        choices=("full", "preview", "all"),
        default="full",
        help="material purpose for bindings of a geometry prim (default full)",
    )


def load(args: argparse.Namespace) -> list[Material]:
    from ..readers import load_materials

    purpose = "" if args.purpose == "all" else args.purpose
    return load_materials(
        args.file,
        time=args.time,
        variants=args.variant or None,
        uv=tuple(args.uv),
        material=args.material,
        purpose=purpose,
    )


def _time_code(text):
    """A finite USD time code (nan / inf would silently select no sample)."""
    import argparse
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite time code, got {text!r}")
    return value
