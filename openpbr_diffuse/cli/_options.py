"""Parts every sub-command's parser is built from: the command itself (described by the first
line of its module's docstring), options taking one or more numbers, an output file with
``--force``, and an output file's refusal as a usage error."""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Callable, Iterator, Sequence
from typing import Any


def describe(doc: str) -> str:
    """A command's description: the first line of its module's docstring, without the markup.

    Examples
    --------
    >>> describe("``openpbr-diffuse explore``: write the explorer.\\n\\nMore text.")
    'openpbr-diffuse explore: write the explorer.'
    """
    return doc.splitlines()[0].strip("`").replace("``", "")


def add_command(
    subparsers: argparse._SubParsersAction,
    name: str,
    help: str,
    run: Callable[[argparse.Namespace], int],
    *,
    doc: str | None = None,
    **kwargs: Any,
) -> argparse.ArgumentParser:
    """The parser of sub-command ``name`` (``help``: its line in the list of commands), whose
    ``run`` is called with the parsed arguments.

    ``doc``: the command module's docstring, whose first line (see :func:`describe`) is the
    description; other keywords (``description``, ``epilog``, ...) go to ``add_parser``.

    Examples
    --------
    >>> sub = argparse.ArgumentParser(prog="tool").add_subparsers()
    >>> p = add_command(sub, "hello", "say hello", lambda args: 0, doc="``tool hello``: say hello.")
    >>> p.description, p.parse_args([]).run(None)
    ('tool hello: say hello.', 0)
    """
    if doc is not None:
        kwargs["description"] = describe(doc)
    p = subparsers.add_parser(name, help=help, **kwargs)
    p.set_defaults(run=run)
    return p


def add_numbers(
    p: argparse.ArgumentParser | argparse._ArgumentGroup,
    flag: str,
    *,
    metavar: str,
    help: str,
    default: Sequence[float] | None = None,
) -> None:
    """Option ``flag`` taking one or more numbers (floats; a list, ``default`` when not given).

    Examples
    --------
    >>> p = argparse.ArgumentParser()
    >>> add_numbers(p, "--mu", metavar="MU", help="cosines", default=[1.0])
    >>> p.parse_args(["--mu", "0.5", "1e-3"]).mu, p.parse_args([]).mu
    ([0.5, 0.001], [1.0])
    """
    p.add_argument(flag, type=float, nargs="+", metavar=metavar, default=default, help=help)


def add_number(
    p: argparse.ArgumentParser | argparse._ArgumentGroup,
    flag: str,
    *,
    metavar: str,
    help: str,
    default: float | None = None,
) -> None:
    """Option ``flag`` taking one number (a float; ``default`` when not given).

    Examples
    --------
    >>> p = argparse.ArgumentParser()
    >>> add_number(p, "--roughness", metavar="R", help="r in [0, 1]")
    >>> p.parse_args(["--roughness", "0.5"]).roughness, p.parse_args([]).roughness
    (0.5, None)
    """
    p.add_argument(flag, type=float, metavar=metavar, default=default, help=help)


def add_output(
    p: argparse.ArgumentParser,
    help: str,
    *,
    metavar: str = "FILE",
    required: bool = True,
    force_help: str | None = None,
) -> None:
    """``--out METAVAR`` and ``--force`` (replace it if it exists; ``force_help`` says more).

    Examples
    --------
    >>> p = argparse.ArgumentParser()
    >>> add_output(p, "output file")
    >>> args = p.parse_args(["--out", "x.glsl"])
    >>> args.out, args.force
    ('x.glsl', False)
    """
    p.add_argument("--out", metavar=metavar, required=required, help=help)
    p.add_argument("--force", action="store_true", help=force_help or f"replace {metavar} if it exists")


@contextlib.contextmanager
def refusal_is_usage() -> Iterator[None]:
    """A ``ValueError`` raised inside (a refused ``--out``, a bad option value) becomes the
    command's one-line usage error (``UsageError``, exit status 2).

    Examples
    --------
    >>> with refusal_is_usage():
    ...     raise ValueError("--out x exists: not overwritten (use --force to replace it)")
    Traceback (most recent call last):
    ...
    openpbr_diffuse.cli.main.UsageError: --out x exists: not overwritten (use --force to replace it)
    """
    from .main import UsageError

    try:
        yield
    except ValueError as exc:
        raise UsageError(str(exc)) from None


__all__ = ["add_command", "add_numbers", "add_output", "describe", "refusal_is_usage"]
