"""The material files of the given paths, in a stable order.

Each given folder is searched recursively for USD and MaterialX files (the readers'
``find_material_files``: sorted by path); a given file is taken as it is.  Every file keeps
the path it was found under, so that pages show it relative to that root.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class LibraryFile:
    """A material file: ``path`` (absolute), ``relpath`` (POSIX, relative to the given path
    it was found under; a given file: its name)."""

    path: str
    relpath: str


def list_files(paths: Iterable[str | os.PathLike[str]]) -> list[LibraryFile]:
    """The material files of ``paths`` (folders searched recursively), in order.

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> files = list_files([BUNDLED_MATERIALS])
    >>> files[0].relpath, os.path.isabs(files[0].path)
    ('brick_preview_textured.usda', True)
    >>> [f.relpath for f in files] == sorted(f.relpath for f in files)
    True
    """
    from ..readers import find_material_files

    out = []
    for given in paths:
        root = Path(os.path.abspath(os.fspath(given)))
        for f in find_material_files([root]):
            f = Path(os.path.abspath(f))
            rel = f.relative_to(root).as_posix() if root.is_dir() else f.name
            out.append(LibraryFile(str(f), rel))
    return out


__all__ = ["LibraryFile", "list_files"]
