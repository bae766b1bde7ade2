"""``openpbr-diffuse explore``: write the EON lobe explorer, one offline HTML page.

    openpbr-diffuse explore --out FILE.html [--force]

Sliders for roughness, rho, theta_o and the light; the lobe as a polar plot and lit spheres
(EON, Lambert, QON) computed in WebGL2 by the page's embedded GLSL export.  Nothing is
fetched from the network.  An existing file is never overwritten without ``--force``.
"""

from __future__ import annotations

import argparse


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "explore",
        help="write an offline HTML page exploring the EON lobe (WebGL2, the GLSL export)",
        description=__doc__.splitlines()[0].strip("`").replace("``", ""),
    )
    p.add_argument("--out", metavar="FILE", required=True, help="output HTML file")
    p.add_argument("--force", action="store_true", help="replace FILE if it exists")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ..export.explorer import write_explorer
    from .main import UsageError

    try:
        path = write_explorer(args.out, force=args.force)
    except ValueError as exc:  # a refused --out: one line, exit 2
        raise UsageError(str(exc)) from None
    print(f"wrote {path}; open it in a browser with WebGL2")
    return 0


__all__ = ["add_parser", "run"]
