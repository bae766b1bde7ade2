"""``openpbr-diffuse export``: EON as code a renderer can ship, generated from one source.

One language-neutral source (``templates/eon.neutral``, rendered by :mod:`.render`) holds
every exported function; its constants are read from the package's own modules
(:mod:`.constants`).  :mod:`.languages` adds each language's prelude, header and the
adapters to the signatures ``openpbr-diffuse check`` grades.
"""

from __future__ import annotations

from pathlib import Path

from .languages import LANGS, export_files, export_text, grade_command


def write_export(lang: str, path: str | Path, *, precision: str = "float", force: bool = False) -> Path:
    """Write the ``lang`` export to ``path`` by the project's one rule for output files.

    An existing file is replaced only with ``force``, never through a symbolic link; the
    text goes to a temporary sibling that takes the name once complete.  "mtlx" writes two
    files: ``path`` and ``NAME_genglsl.glsl`` beside it (both checked before either is written).

    Raises
    ------
    ValueError
        ``lang`` or ``precision`` unknown, ``precision`` "double" for a language without
        double precision, or ``path`` may not be written (``OutputExistsError`` when it
        exists and ``force`` is false).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> out = write_export("glsl", pathlib.Path(tempfile.mkdtemp()) / "eon.glsl")
    >>> out.read_text().startswith("// EON")
    True
    """
    from .._outfile import check_output_file, write_output_file

    check_output_file(Path(path), option="--out", force=force)  # before any work
    files = export_files(lang, path, precision)
    for target, _ in files[1:]:
        check_output_file(target, option="--out (its sibling)", force=force)
    for target, text in files[1:]:
        write_output_file(target, text, option="--out (its sibling)", force=force)
    return write_output_file(path, files[0][1], option="--out", force=force)


__all__ = ["LANGS", "export_files", "export_text", "grade_command", "write_export"]
