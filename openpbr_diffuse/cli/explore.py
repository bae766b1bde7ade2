"""``openpbr-diffuse explore``: write the EON lobe explorer, one offline HTML page.

    openpbr-diffuse explore --out FILE.html [--force]

Sliders for roughness, rho, theta_o and the light; the lobe as a polar plot and lit spheres
(EON, Lambert, QON) computed in WebGL2 by the page's embedded GLSL export.  Nothing is
fetched from the network.  An existing file is never overwritten without ``--force``.
"""

from __future__ import annotations

import argparse

from ._options import add_command, add_output, refusal_is_usage

#: The command's line in ``openpbr-diffuse --help``.
HELP = "write an offline HTML page exploring the EON lobe (WebGL2, the GLSL export)"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "explore", HELP, run, doc=__doc__)
    add_output(p, "output HTML file")
    return p


def run(args: argparse.Namespace) -> int:
    from ..export.explorer import write_explorer

    with refusal_is_usage():  # a refused --out: one line, exit 2
        path = write_explorer(args.out, force=args.force)
    print(f"wrote {path}; open it in a browser with WebGL2")
    return 0


__all__ = ["add_parser", "run"]
