"""Reading the shipped CSV tables whose provenance header is ``# key: value`` lines."""

from __future__ import annotations

import csv
import os
from pathlib import Path


def read_headed_csv(path: str | os.PathLike[str]) -> tuple[dict[str, str], list[str], list[list[str]]]:
    """(header {key: value}, column names, rows of str) of a CSV with a ``#`` header.

    Header lines are ``# key: value`` (anywhere before or between rows); blank lines are
    skipped; the first non-comment line names the columns.
    """
    header, lines = {}, []
    with Path(path).open(encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("#"):
                key, _, value = line[1:].strip().partition(":")
                header[key.strip()] = value.strip()
            elif line.strip():
                lines.append(line)
    reader = csv.reader(lines)
    names = next(reader)
    return header, names, list(reader)
