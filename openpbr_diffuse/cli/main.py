"""``openpbr-diffuse``: entry point and sub-command dispatch.

Each sub-command lives in its own module of this package, exposing
``add_parser(subparsers)`` and ``run(args) -> int``.

Conventions (tested in ``tests/test_cli_conventions.py``):

- unusable input (``ValueError``, ``TypeError``, ``OSError``, ``UsageError``, argparse
  errors) prints one line ``openpbr-diffuse COMMAND: error: ...`` on stderr, exit 2; an
  OSError names its file (a failed write to standard output names that);
- NumPy's floating-point RuntimeWarnings are not printed (the commands account for
  overflow and NaN in what they print); the library itself still issues them;
- arguments that read as numbers (``-1e-300``, ``-inf``, ``-.5``) are values, never options;
- a closed output pipe (``... | head -2``) ends the command quietly with exit status 141
  (128 + SIGPIPE: what a C tool killed by SIGPIPE reports, so ``set -o pipefail`` still
  sees that the output was cut short);
- Ctrl-C prints ``openpbr-diffuse: interrupted`` and exits 130 (128 + SIGINT), no traceback.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import re
import sys
import warnings
from collections.abc import Iterable

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
    "template": "template",
    "chart": "chart",
    "export": "export",
    "explore": "explore",
}

PROG = "openpbr-diffuse"
DESCRIPTION = (
    "Reference implementation and conformance validator of the OpenPBR rough diffuse "
    "lobe (EON, Portsmouth-Kutz-Hill JCGT 2025) and the Oren-Nayar family."
)
EXIT_USAGE, EXIT_SIGPIPE, EXIT_SIGINT = 2, 141, 130

#: Any float literal Python's float() reads, with a leading minus: taken as a value.
#: (argparse's own pattern knows only -1 and -1.5, so -1e-300 and -inf became options.)
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


class UsageError(Exception):
    """Raised by a command for input it cannot use (exit status 2)."""

    def __init__(self, message: str, prog: str | None = None) -> None:
        super().__init__(message)
        self.prog = prog


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message):  # argparse's multi-line usage dump -> one line, exit 2
        raise UsageError(message, prog=self.prog)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description=DESCRIPTION, epilog=f"Run '{PROG} COMMAND --help' for a command's options.")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for _name, module in COMMANDS.items():
        importlib.import_module(f"{__package__}.{module}").add_parser(sub)
    return parser


#: Errors of a write whose file the OS does not name (a full disk, a quota, a size limit).
_WRITE_ERRNOS = {errno.ENOSPC, errno.EFBIG, errno.EROFS, getattr(errno, "EDQUOT", errno.ENOSPC)}
#: The name a failed write to standard output is given.
STDOUT_NAME = "standard output"


def _message(exc, args=None):
    """One line for an exception; OSErrors as 'reason: path', not '[Errno 17] ...'.

    An OSError the OS raised without a file name (a write or close on a full disk) names the
    command's ``--out`` when it has one; a message that starts with the command's own name
    ("report: ...") does not repeat it after ``openpbr-diffuse report: error:``.
    """
    if isinstance(exc, OSError) and exc.strerror:
        if exc.filename is not None:
            return f"{exc.strerror}: {exc.filename}"
        out = getattr(args, "out", None)
        if out is not None and exc.errno in _WRITE_ERRNOS:
            return f"{exc.strerror} (while writing {out})"
        return exc.strerror
    text = " ".join(str(exc).split()) or type(exc).__name__
    command = getattr(args, "command", None)
    if command and text.startswith(f"{command}: "):
        text = text[len(command) + 2 :]
    return text


class _NamedStdout:
    """``sys.stdout`` whose failed writes name it: the OSError of a write to a full disk
    carries no file name.  A closed pipe (BrokenPipeError) passes unchanged."""

    def __init__(self, stream):
        self._stream = stream

    def __getattr__(self, name):
        return getattr(self._stream, name)

    def _named(self, exc):
        if isinstance(exc, BrokenPipeError) or exc.filename is not None or exc.errno is None:
            return exc
        return OSError(exc.errno, exc.strerror, STDOUT_NAME)

    def write(self, text):
        try:
            return self._stream.write(text)
        except OSError as exc:
            raise self._named(exc) from None

    def writelines(self, lines):
        for line in lines:
            self.write(line)

    def flush(self):
        try:
            return self._stream.flush()
        except OSError as exc:
            raise self._named(exc) from None


def _silence_stdout():
    """After EPIPE: point stdout at /dev/null so the interpreter's final flush stays quiet."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no real file descriptor (e.g. captured)
        pass


def _suggest(word: str, choices: Iterable[str]) -> str:
    """`` (did you mean X?)`` for the closest of ``choices`` to ``word``, or ``""``."""
    import difflib

    close = difflib.get_close_matches(word.split("=", 1)[0], list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def _parse(parser: argparse.ArgumentParser, argv: list[str] | None) -> argparse.Namespace:
    """``parse_args`` whose one-line errors name the closest option or command and the usage."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    words = sys.argv[1:] if argv is None else list(argv)
    command = next((w for w in words if not w.startswith("-")), None)
    if command is not None and command not in sub.choices:
        raise UsageError(
            f"unknown command {command!r}{_suggest(command, sub.choices)}; choose from {', '.join(sub.choices)}",
            prog=PROG,
        )
    args, extra = parser.parse_known_args(argv)
    if extra:
        cmd = sub.choices[args.command]
        options = [o for a in cmd._actions for o in a.option_strings]
        usage = " ".join(cmd.format_usage().split())
        raise UsageError(f"unrecognized argument {extra[0]}{_suggest(extra[0], options)}; {usage}", prog=cmd.prog)
    return args


def main(argv: list[str] | None = None) -> int:
    from .. import _signals

    _signals.install()  # SIGTERM/SIGHUP like Ctrl-C: clean up, exit 128 + signum
    stdout = sys.stdout
    if stdout is not None:
        sys.stdout = _NamedStdout(stdout)
    try:
        with warnings.catch_warnings():
            # NumPy's "overflow encountered in ..." lines are not for the user of a command
            warnings.simplefilter("ignore", RuntimeWarning)
            return _run_command(argv, _signals)
    finally:
        if sys.stdout is not None and isinstance(sys.stdout, _NamedStdout):
            sys.stdout = stdout


def _run_command(argv, _signals):
    prog, args = PROG, None
    try:
        parser = build_parser()
        args = _parse(parser, argv)
        prog = f"{PROG} {args.command}"
        code = int(args.run(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, inside the handler, not at exit
        return code
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_SIGPIPE
    except KeyboardInterrupt as exc:
        signum = getattr(exc, "signum", None) or _signals.received() or 2
        print(f"{PROG}: interrupted" + ("" if signum == 2 else f" ({exc})"), file=sys.stderr)
        return 128 + signum
    except UsageError as exc:
        print(f"{exc.prog or prog}: error: {_message(exc, args)}", file=sys.stderr)
        return EXIT_USAGE
    except (ValueError, TypeError, OSError) as exc:
        if isinstance(exc, OSError) and exc.filename == STDOUT_NAME:
            _silence_stdout()  # what could not be written stays unwritten, not retried at exit
        print(f"{prog}: error: {_message(exc, args)}", file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":
    # `python -m openpbr_diffuse.cli.main`: run the imported module's main, so that the
    # UsageError the sub-commands import (openpbr_diffuse.cli.main.UsageError) is the class
    # caught here, not a second copy defined in __main__
    from openpbr_diffuse.cli.main import main as _main

    sys.exit(_main())
