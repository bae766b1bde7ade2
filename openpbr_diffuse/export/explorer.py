"""The lobe explorer: one offline HTML page that runs the GLSL export in WebGL2.

Sliders for r, rho (RGB), theta_o and the light (theta_i, phi); a polar plot of f mu_i in the
plane of incidence and three lit spheres (EON, Lambert, QON), all computed by the text of
``openpbr-diffuse export --lang glsl`` embedded in the page (GLSL ES 3.00 accepts it as is,
after ``#version 300 es`` and ``precision highp float``).  Nothing is fetched: no CDN, no
file beside it.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .._version import __version__
from .languages import export_text


def explorer_html() -> str:
    """The page's text.

    Examples
    --------
    >>> page = explorer_html()
    >>> "vec3 eon_f(vec3 wi, vec3 wo, float roughness, vec3 rho)" in page, "src=" in page
    (True, False)
    """
    template = resources.files(__package__).joinpath("templates").joinpath("explore.html").read_text(encoding="utf-8")
    glsl = export_text("glsl")
    if "</script" in glsl.lower():  # cannot happen with the neutral source; kept as a guard of the page's syntax
        raise ValueError("the GLSL export holds '</script': it cannot be embedded")
    return template.replace("{VERSION}", __version__).replace("{EON_GLSL}", glsl.strip())


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


__all__ = ["explorer_html", "write_explorer"]
