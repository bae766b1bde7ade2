"""``openpbr-diffuse export``: write EON as one self-contained source file for a renderer.

    openpbr-diffuse export --lang glsl|wgsl|cpp|osl|mtlx [--precision float|double] --out FILE [--force]

Every language is rendered from the package's one source of the functions (its constants
read from the package's own modules); the file's ``// grade:`` line is the ``check``
command that grades it.  ``--lang mtlx`` writes FILE (a MaterialX nodedef) and its GLSL
implementation ``NAME_genglsl.glsl`` beside it.  An existing file is never overwritten
without ``--force``.
"""

from __future__ import annotations

import argparse


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    from ..export import LANGS

    p = subparsers.add_parser(
        "export",
        help="write EON (f, albedo, sampler, pdf) as GLSL, WGSL, C++, OSL or a MaterialX node",
        description=__doc__.splitlines()[0].strip("`").replace("``", ""),
    )
    p.add_argument("--lang", required=True, choices=LANGS, help="the language of the file")
    p.add_argument(
        "--precision", choices=("float", "double"), default="float", help="arithmetic (double: cpp only; default float)"
    )
    p.add_argument("--out", metavar="FILE", required=True, help="output file")
    p.add_argument("--force", action="store_true", help="replace FILE if it exists")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ..export import grade_command, write_export
    from .main import UsageError

    try:
        path = write_export(args.lang, args.out, precision=args.precision, force=args.force)
    except ValueError as exc:  # unknown precision for the language, a refused --out: one line, exit 2
        raise UsageError(str(exc)) from None
    if args.lang == "mtlx":
        from ..export.mtlx import glsl_name

        print(f"wrote {path} and {path.with_name(glsl_name(path))} (its genglsl implementation)")
    else:
        print(f"wrote {path}; grade: {grade_command(args.lang, str(path))}")
    return 0


__all__ = ["add_parser", "run"]
