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

from ._options import add_command, add_output, refusal_is_usage

#: The command's line in ``openpbr-diffuse --help``.
HELP = "write EON (f, albedo, sampler, pdf) as GLSL, WGSL, C++, OSL or a MaterialX node"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    from ..export import LANGS

    p = add_command(subparsers, "export", HELP, run, doc=__doc__)
    p.add_argument("--lang", required=True, choices=LANGS, help="the language of the file")
    p.add_argument(
        "--precision", choices=("float", "double"), default="float", help="arithmetic (double: cpp only; default float)"
    )
    add_output(p, "output file")
    return p


def run(args: argparse.Namespace) -> int:
    from ..export import grade_command, write_export

    with refusal_is_usage():  # unknown precision for the language, a refused --out: one line, exit 2
        path = write_export(args.lang, args.out, precision=args.precision, force=args.force)
    if args.lang == "mtlx":
        from ..export.mtlx import glsl_name

        print(f"wrote {path} and {path.with_name(glsl_name(path))} (its genglsl implementation)")
    else:
        print(f"wrote {path}; grade: {grade_command(args.lang, str(path))}")
    return 0


__all__ = ["add_parser", "run"]
