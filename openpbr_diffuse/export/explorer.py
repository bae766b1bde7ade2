"""The lobe explorer: one offline HTML page that runs the GLSL export in WebGL2.

Sliders for r, rho (RGB), theta_o and the light (theta_i, phi); a polar plot of f mu_i in the
plane of incidence and three lit spheres (EON, Lambert, QON), all computed by the text of
``openpbr-diffuse export --lang glsl`` embedded in the page (GLSL ES 3.00 accepts it as is,
after ``#version 300 es`` and ``precision highp float``).  Nothing is fetched: no CDN, no
file beside it.

With an implementation under test (``openpbr-diffuse report --glsl FILE --function NAME``), the
page also holds that GLSL, escaped (``&``, ``<`` and ``>`` as entities, which the page's script
decodes: the block holds no ``<`` at all, so no ``</script>`` or ``<!--`` in the code can end or
change it), compiles it with the same harness in a second program, and shows theirs, the
reference EON and ``|theirs - reference|`` with its maximum.  The page's one script is allowed by
its SHA-256 in a Content-Security-Policy: no other script can run.
"""

from __future__ import annotations

import base64
import hashlib
import html
import re
from importlib import resources
from pathlib import Path

from .._version import __version__
from .languages import export_text

#: the largest implementation GLSL the page embeds (characters); a larger one is named, not embedded
MAX_SUBJECT_CHARS = 1 << 20
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def escape_shader(code: str) -> str:
    """GLSL text as the page embeds it in a ``<script type="x-shader">`` block: ``&``, ``<`` and
    ``>`` as ``&amp;``, ``&lt;`` and ``&gt;`` (the page's script decodes them).

    Examples
    --------
    >>> escape_shader("a < b && c > d // </script>")
    'a &lt; b &amp;&amp; c &gt; d // &lt;/script&gt;'
    """
    return code.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _subject_block(code: str | None, function: str | None, name: str, message: str) -> str:
    if code is None and not message:
        return ""
    if not isinstance(function, str) or not _IDENTIFIER.fullmatch(function):
        raise ValueError(f"function: expected a GLSL identifier, got {function!r}")
    if code is not None and len(code) > MAX_SUBJECT_CHARS:
        message = f"Its GLSL ({len(code)} characters) is larger than the page embeds ({MAX_SUBJECT_CHARS})."
        code = None
    attrs = f'data-function="{function}" data-name="{html.escape(name, quote=True)}"'
    if message:
        attrs += f' data-message="{html.escape(message, quote=True)}"'
    return f'<script id="subject-glsl" type="x-shader/x-fragment" {attrs}>\n{escape_shader(code or "")}\n</script>'


def _script_hash(page: str) -> str:
    """The CSP source of the template's one executable script (its last ``<script>`` block)."""
    body = page[page.rindex("<script>") + len("<script>") : page.rindex("</script>")]
    return "'sha256-" + base64.b64encode(hashlib.sha256(body.encode("utf-8")).digest()).decode() + "'"


def explorer_html(
    subject_glsl: str | None = None, subject_function: str | None = None, subject_name: str = "", message: str = ""
) -> str:
    """The page's text.

    Parameters
    ----------
    subject_glsl : str, optional
        The GLSL of an implementation under test (includes resolved, defines written as
        ``#define`` lines): the page shows its ``subject_function`` beside the reference EON,
        with ``|theirs - reference|``.
    subject_function : str, optional
        Its BRDF function, ``vec3 NAME(vec3 wi, vec3 wo, float roughness, vec3 rho)``.
    subject_name : str
        How the page names it (e.g. the file's name).
    message : str
        Why its GLSL is not embedded (shown instead of its spheres).

    Raises
    ------
    ValueError
        ``subject_function`` is not a GLSL identifier.

    Examples
    --------
    >>> page = explorer_html()
    >>> "vec3 eon_f(vec3 wi, vec3 wo, float roughness, vec3 rho)" in page, "src=" in page
    (True, False)
    >>> page = explorer_html("vec3 f(vec3 a, vec3 b, float r, vec3 c) { return c; } // </script>", "f", "mine.glsl")
    >>> "// &lt;/script&gt;" in page, page.count("</script>")
    (True, 3)
    """
    template = resources.files(__package__).joinpath("templates").joinpath("explore.html").read_text(encoding="utf-8")
    glsl = export_text("glsl")
    if "</script" in glsl.lower():  # cannot happen with the neutral source; kept as a guard of the page's syntax
        raise ValueError("the GLSL export holds '</script': it cannot be embedded")
    page = (
        template.replace("{SCRIPT_HASH}", _script_hash(template))
        .replace("{VERSION}", __version__)
        .replace("{EON_GLSL}", glsl.strip())
    )  # the implementation's text last: nothing is replaced inside it
    return page.replace("{SUBJECT_BLOCK}", _subject_block(subject_glsl, subject_function, subject_name, message))


def write_explorer(path: str | Path, *, force: bool = False) -> Path:
    """Write the explorer page to ``path`` by the project's rule for output files.

    Raises
    ------
    ValueError
        ``path`` may not be written (``OutputExistsError`` when it exists and ``force`` is false).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> out = write_explorer(pathlib.Path(tempfile.mkdtemp()) / "eon.html")
    >>> out.read_text().startswith("<!DOCTYPE html>")
    True
    """
    from .._outfile import check_output_file, write_output_file

    check_output_file(Path(path), option="--out", force=force)
    return write_output_file(path, explorer_html(), option="--out", force=force)


__all__ = ["MAX_SUBJECT_CHARS", "escape_shader", "explorer_html", "write_explorer"]
