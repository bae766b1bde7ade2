"""``openpbr-diffuse``: entry point and sub-command dispatch.

Each sub-command lives in its own module of this package, exposing
``add_parser(subparsers)`` and ``run(args) -> int``.  Unusable input (``ValueError``,
``TypeError``, ``OSError``, ``UsageError``) prints one line on stderr and exits 2.
"""
import argparse
import importlib
import sys

from .._version import __version__

#: sub-command name -> module in this package (added as the commands are built).
COMMANDS = {
    "albedo": "albedo",
    "vectors": "vectors",
    "check": "check",
    "report": "report",
    "colorshift": "colorshift",
    "eval": "eval",
    "render": "render",
    "simulate": "simulate",
}


class UsageError(Exception):
    """Raised by a command for input it cannot use (exit status 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse's multi-line usage dump -> one line, exit 2
        raise UsageError(f"{self.prog}: {message}")


def build_parser():
    parser = _Parser(prog="openpbr-diffuse", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"openpbr-diffuse {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name, module in COMMANDS.items():
        importlib.import_module(f"{__package__}.{module}").add_parser(sub)
    return parser


def main(argv=None):
    try:
        args = build_parser().parse_args(argv)
        return int(args.run(args) or 0)
    except (UsageError, ValueError, TypeError, OSError) as exc:
        print(f"openpbr-diffuse: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
