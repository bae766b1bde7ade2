"""Reading the shipped CSV tables whose provenance header is ``# key: value`` lines."""

from __future__ import annotations

import csv
import os
from pathlib import Path

from ._textfiles import named, not_utf8


def read_headed_csv(path: str | os.PathLike[str]) -> tuple[dict[str, str], list[str], list[list[str]]]:
    """(header {key: value}, column names, rows of str) of a CSV with a ``#`` header.

    Header lines are ``# key: value`` (anywhere before or between rows); blank lines are
    skipped; the first non-comment line names the columns.  A file that is not UTF-8 text,
    has no column row or is not valid CSV is a ValueError naming it.

    Examples
    --------
    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "t.csv")
    >>> _ = open(p, "w").write("# source: measured\\nmu,E\\n0.5,0.25\\n")
    >>> read_headed_csv(p)
    ({'source': 'measured'}, ['mu', 'E'], [['0.5', '0.25']])
    """
    header, lines = {}, []
    try:
        with Path(path).open(encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("#"):
                    key, _, value = line[1:].strip().partition(":")
                    header[key.strip()] = value.strip()
                elif line.strip():
                    lines.append(line)
    except UnicodeDecodeError:
        raise not_utf8(path) from None
    except OSError as exc:
        raise named(exc, path) from None
    reader = csv.reader(lines)
    try:
        names = next(reader)
        rows = list(reader)
    except StopIteration:
        raise ValueError(f"{path}: no column row (the file holds only # lines or nothing)") from None
    except csv.Error as exc:
        raise ValueError(f"{path}: not valid CSV ({exc})") from None
    return header, names, rows
