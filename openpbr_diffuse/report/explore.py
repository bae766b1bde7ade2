"""The lobe explorer in the report: ``explore.html`` beside ``index.html``.

Every report holds the explorer page of ``openpbr-diffuse explore`` (the GLSL export in
WebGL2).  With a GLSL implementation under test (``report --glsl FILE --function NAME``), the
page also shows that function beside the reference EON, and ``|theirs - reference|`` with its
largest value, compiled by WebGL2 (GLSL ES 3.00) with the explorer's harness; when it does not
compile there (a desktop GLSL 4.x construct), the page says so in one line.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

#: the explorer's file name in the report folder
EXPLORE_FILE = "explore.html"


@dataclass
class ExplorerSubject:
    """The GLSL the explorer shows beside the reference.

    ``code`` is the file's text with its includes resolved and the defines as ``#define``
    lines (None when it cannot be read: ``message`` says why); ``function`` the BRDF
    function; ``name`` how the page names it.
    """

    name: str
    function: str
    code: str | None
    message: str = ""


def explorer_subject(
    path: str | os.PathLike[str],
    function: str,
    includes: Sequence[str | os.PathLike[str]] = (),
    defines: Sequence[str] = (),
) -> ExplorerSubject:
    """The explorer's view of ``report --glsl path --function function``.

    An include that is missing or a file that cannot be read gives ``code=None`` and the
    reason in ``message`` (the grade says the same in its own words).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "mine.glsl"
    >>> _ = p.write_text("vec3 f(vec3 wi, vec3 wo, float r, vec3 rho) { return rho * K; }")
    >>> s = explorer_subject(p, "f", defines=["K=0.5"])
    >>> s.name, s.code.splitlines()[0], s.message
    ('mine.glsl', '#define K 0.5', '')
    """
    from ..graders import glsl, limits

    path = Path(path)
    try:
        defs = limits.parse_defines(defines)
        code = glsl.resolve_includes(path, tuple(Path(i) for i in includes))
    except (OSError, ValueError) as exc:  # GraderUnavailable is an OSError; UnicodeDecodeError a ValueError
        return ExplorerSubject(path.name, function, None, f"Its GLSL could not be read: {' '.join(str(exc).split())}")
    head = "".join(f"#define {k} {v}\n" for k, v in defs.items())
    return ExplorerSubject(path.name, function, head + code)


def write_explorer_into(folder: Path, subject: ExplorerSubject | None = None) -> dict:
    """Write ``explore.html`` into the report's staging ``folder``; what ``report.json`` says of it.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> write_explorer_into(folder)
    {'file': 'explore.html', 'subject': None, 'function': None, 'message': ''}
    >>> (folder / "explore.html").read_text().startswith("<!DOCTYPE html>")
    True
    """
    from ..export.explorer import explorer_html

    if subject is None:
        page = explorer_html()
    else:
        page = explorer_html(subject.code, subject.function, subject.name, subject.message)
    (Path(folder) / EXPLORE_FILE).write_text(page, encoding="utf-8")
    return {
        "file": EXPLORE_FILE,
        "subject": None if subject is None else subject.name,
        "function": None if subject is None else subject.function,
        "message": "" if subject is None else subject.message,
    }


__all__ = ["EXPLORE_FILE", "ExplorerSubject", "explorer_subject", "write_explorer_into"]
