"""Colour spaces of authored colours, converted to the one working space: ACEScg.

Every colour the readers resolve is returned in **ACEScg** (linear AP1 primaries, ACES white
point; ``lin_ap1_scene`` in USD, ``acescg`` in MaterialX): OpenPBR's default colour space, so
OpenPBR documents in ``acescg`` pass through unchanged.  The library's nodes take the colour
as it is given (they are colour-space agnostic).

The colour spaces are those MaterialX knows -- its colour-management library (``cmlib``:
``lin_rec709``, ``srgb_texture``, ``g18_rec709``, ``g22_rec709``, ``rec709_display``,
``acescg``, ``g22_ap1``, ``lin_adobergb``, ``adobergb``, ``lin_displayp3``,
``srgb_displayp3``) with the names its default colour-management system remaps
(``gamma18``, ``gamma22``, ``gamma24``, ``lin_ap1``) -- and every scene-referred space of the
OpenColorIO ACES configuration MaterialX's OCIO colour management reads (``ACES2065-1``,
``ACEScc``, ``ACEScct``, ``lin_rec2020``, ``CIE XYZ-D65 - Scene-referred``, ...) under all
their OpenColorIO aliases (``Utility - Linear - sRGB``, ``sRGB - Texture``, ``lin_srgb``,
...), USD's ``Gf.ColorSpaceNames`` tokens (``lin_rec709_scene``, ...) and colour-science's
names.  Display-referred OpenColorIO spaces (``sRGB - Display``) are refused with that reason.

The conversions are colour-science's (``colour.RGB_COLOURSPACES``, ``matrix_RGB_to_RGB`` with
the Bradford adaptation the ACES configuration uses, matrices derived from the primaries and white point as
OpenColorIO derives them, ``XYZ_to_RGB``, the colour spaces'
``cctf_decoding``), never typed by hand.  colour-science takes about a second to import, which
an ``eval`` of one file cannot afford, so its results are held in ``_colorspace_table``,
written by ``build_table()`` (``python -m openpbr_diffuse.readers.colorspace --write``); a test
checks the table against colour-science.  The decoding curves there are colour-science's own
kinds: the sRGB curve (``eotf_sRGB``) and pure powers (``gamma_function``), evaluated in
closed form in double precision (negative values: sRGB's linear segment, 0 for powers, as
MaterialX's ``cmlib`` graphs clamp them); any other curve (ACEScc, ACEScct) is
colour-science's ``cctf_decoding``, imported on first use.
"""

from __future__ import annotations

import functools
import sys
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import _colorspace_table as _table

_SPACES: dict[str, Any] = _table.SPACES  # generated: name -> matrix, decoding, ...

#: The working colour space of every resolved colour (MaterialX / USD names).
WORKING_SPACE = "acescg"
WORKING_SPACE_USD = "lin_ap1_scene"

#: canonical name -> (OpenColorIO name, colour-science colour space giving the primaries and
#: white point, colour-science decoding: None = that colour space's own ``cctf_decoding``, else
#: a name of ``colour.CCTF_DECODINGS``).  The only hand-written part: names.
SPECS = {
    "lin_rec709": ("Linear Rec.709 (sRGB)", "Linear Rec.709 (sRGB)", None),
    "srgb_texture": ("sRGB Encoded Rec.709 (sRGB)", "sRGB Encoded Rec.709 (sRGB)", None),
    "g18_rec709": ("Gamma 1.8 Encoded Rec.709", "Gamma 1.8 Encoded Rec.709", None),
    "g22_rec709": ("Gamma 2.2 Encoded Rec.709", "Gamma 2.2 Encoded Rec.709", None),
    "g24_rec709": ("Gamma 2.4 Encoded Rec.709", "Linear Rec.709 (sRGB)", "Gamma 2.4"),
    "acescg": ("ACEScg", "ACEScg", None),
    "aces2065-1": ("ACES2065-1", "ACES2065-1", None),
    "acescc": ("ACEScc", "ACEScc", None),
    "acescct": ("ACEScct", "ACEScct", None),
    "g22_ap1": ("Gamma 2.2 Encoded AP1", "Gamma 2.2 Encoded AP1", None),
    "srgb_ap1": ("sRGB Encoded AP1", "sRGB Encoded AP1", None),
    "lin_adobergb": ("Linear AdobeRGB", "Linear AdobeRGB", None),
    # Adobe RGB (1998)'s exponent 563/256, as MaterialX's cmlib, OpenColorIO and Gf.ColorSpace use
    "adobergb": ("Gamma 2.2 Encoded AdobeRGB", "Adobe RGB (1998)", None),
    "lin_displayp3": ("Linear P3-D65", "Linear P3-D65", None),
    "srgb_displayp3": ("sRGB Encoded P3-D65", "sRGB Encoded P3-D65", None),
    "lin_rec2020": ("Linear Rec.2020", "Linear Rec.2020", None),
    "lin_ciexyzd65": ("CIE XYZ-D65 - Scene-referred", "CIE XYZ-D65 - Scene-referred", None),
}
#: Names MaterialX's default colour-management system remaps (DefaultColorManagementSystem),
#: UsdUVTexture's ``sRGB`` and the raw / data spellings.
EXTRA_ALIASES = {
    "gamma18": "g18_rec709",
    "gamma22": "g22_rec709",
    "gamma24": "g24_rec709",
    "rec709_display": "g24_rec709",
    "lin_ap1": "acescg",
    "lin_ap0": "aces2065-1",
    "srgb": "srgb_texture",
    "raw": "raw",
    "data": "raw",
    "identity": "raw",
    "none": "raw",
    "utility - raw": "raw",
    "": "raw",
}


def _colour():
    """colour-science (imported without its plotting sub-package; see ``openpbr_diffuse._colour``)."""
    colour = sys.modules.get("colour")
    if colour is not None:
        return colour
    from .._colour import _colour as load

    return load()


def _decoding_kind(fn: Any) -> tuple:
    """A colour-science decoding function as ("linear",), ("srgb",), ("gamma", exponent) or
    ("colour", None) -- the last evaluated by colour-science itself at run time."""
    colour = _colour()
    base = fn.func if isinstance(fn, functools.partial) else fn
    gamma = colour.models.rgb.transfer_functions.gamma_function
    if base is colour.models.rgb.transfer_functions.linear_function:
        return ("linear",)
    if base is colour.models.rgb.transfer_functions.eotf_sRGB:
        return ("srgb",)
    if base is gamma and isinstance(fn, functools.partial) and set(fn.keywords) == {"exponent"} and not fn.args:
        return ("gamma", float(fn.keywords["exponent"]))
    return ("colour", None)


def _derived(cs):
    """A copy of colour-science's colour space ``cs`` whose RGB <-> XYZ matrices are derived from
    its primaries and white point, as OpenColorIO's and Gf.ColorSpace's are (some published
    matrices, Adobe RGB (1998)'s, are rounded: white would not map to white)."""
    cs = cs.copy()
    cs.use_derived_transformation_matrices(True)
    return cs


def build_table() -> dict:
    """The colour-space table computed with colour-science and OpenColorIO's names.

    Returns ``{"spaces": {canonical: {"ocio", "colour", "decoding", "matrix"}}, "aliases":
    {lower-case name: canonical}, "display": [display-referred OpenColorIO names]}``:
    ``matrix`` takes the space's linear values to ACEScg (rows: output channels; Bradford
    adaptation to the ACES white point); ``decoding`` is ``_decoding_kind`` of the space's
    decoding, with the colour-science name for ("colour", ...).  The aliases are the
    OpenColorIO aliases of OpenImageIO's built-in ACES configuration, colour-science's keys of
    the same colour space, and ``EXTRA_ALIASES``.

    Examples
    --------
    >>> t = build_table()
    >>> t["aliases"]["utility - linear - srgb"], t["spaces"]["g22_rec709"]["decoding"]
    ('lin_rec709', ['gamma', 2.2])
    """
    import OpenImageIO as oiio

    colour = _colour()
    dst = _derived(colour.RGB_COLOURSPACES["ACEScg"])
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    config = oiio.ColorConfig()
    spaces, aliases = {}, {}
    for canon, (ocio, cname, cctf) in SPECS.items():
        cs = _derived(colour.RGB_COLOURSPACES[cname])
        if canon == "lin_ciexyzd65":  # CIE XYZ of a D65-adapted scene (OpenColorIO's reference)
            m = colour.XYZ_to_RGB(np.eye(3), dst, d65, "Bradford").T
        else:
            m = colour.matrix_RGB_to_RGB(cs, dst, "Bradford")
        if np.allclose(m, np.eye(3), rtol=0, atol=1e-12):  # AP1 primaries: the identity, without round-off
            m = np.eye(3)
        fn = colour.CCTF_DECODINGS[cctf] if cctf else cs.cctf_decoding
        kind = _decoding_kind(fn)
        if kind[0] == "colour":
            kind = ("colour", cctf or cname)
        spaces[canon] = {
            "ocio": ocio,
            "colour": cname,
            "decoding": list(kind),
            "matrix": [[float(x) for x in row] for row in np.asarray(m, dtype=np.float64)],
        }
        names = {canon, ocio}
        names |= (
            {a.removeprefix("ocio:") for a in config.getAliases(ocio)} if ocio in config.getColorSpaceNames() else set()
        )
        if cctf is None:
            same = colour.RGB_COLOURSPACES[cname]
            names |= {k for k in colour.RGB_COLOURSPACES.keys() if colour.RGB_COLOURSPACES[k] is same}
        for n in names:
            aliases[n.strip().lower()] = canon
    for n in config.getAliases("Raw") + ["Raw"]:
        aliases[n.strip().lower()] = "raw"
    aliases.update(EXTRA_ALIASES)
    display = sorted(
        n
        for n in config.getColorSpaceNames()
        if n.lower() not in aliases and config.getColorSpaceFamilyByName(n) == "Display"
    )
    display_aliases = sorted({a.lower() for n in display for a in [n] + list(config.getAliases(n))} - set(aliases))
    return {"spaces": spaces, "aliases": dict(sorted(aliases.items())), "display": display_aliases}


def write_table(path: str | None = None) -> str:
    """Write ``build_table()`` as the Python module ``_colorspace_table`` (or to ``path``).

    Examples
    --------
    >>> import os, tempfile
    >>> out = write_table(os.path.join(tempfile.mkdtemp(), "table.py"))
    >>> "GENERATED by ``colorspace.build_table()``" in open(out).read()
    True
    """
    import os
    import pprint

    path = path or os.path.join(os.path.dirname(__file__), "_colorspace_table.py")
    t = build_table()
    # each matrix once, under the name of the (first) linear space of its primaries
    spaces = dict(sorted(t["spaces"].items(), key=lambda item: (item[1]["decoding"] != ["linear"], item[0])))
    matrices: dict[str, list] = {}
    for name, spec in spaces.items():
        if spec["matrix"] not in matrices.values():
            matrices[name] = spec["matrix"]
    key = {name: next(k for k, m in matrices.items() if m == spec["matrix"]) for name, spec in spaces.items()}
    rows = "".join(
        f"    {name!r}: {(spec['ocio'], spec['colour'], spec['decoding'], key[name])!r},\n"
        for name, spec in sorted(t["spaces"].items())
    )
    text = (
        '"""Colour-space table of ``colorspace``: GENERATED by ``colorspace.build_table()`` from\n'
        "colour-science and OpenColorIO's names (``python -m openpbr_diffuse.readers.colorspace --write``);\n"
        'do not edit by hand (a test checks it against colour-science)."""\n\n'
        "#: linear space -> the matrix from it to ACEScg (rows: output channels), shared by the spaces\n"
        "#: of the same primaries.\n"
        f"MATRICES = {pprint.pformat(dict(sorted(matrices.items())), width=110)}\n\n"
        "#: canonical name -> (OpenColorIO name, colour-science name, decoding, key of MATRICES).\n"
        f"_ROWS = {{\n{rows}}}\n\n"
        "SPACES = {\n"
        "    name: {'colour': colour, 'decoding': decoding, 'matrix': MATRICES[primaries], 'ocio': ocio}\n"
        "    for name, (ocio, colour, decoding, primaries) in _ROWS.items()\n"
        "}\n\n"
        f"ALIASES = {pprint.pformat(t['aliases'], width=110)}\n\n"
        f"DISPLAY = {pprint.pformat(t['display'], width=110)}\n"
    )
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)
    return path


def known() -> list:
    """The canonical names of the supported colour spaces (and "raw").

    Examples
    --------
    >>> "g22_rec709" in known() and "lin_ciexyzd65" in known()
    True
    """
    return sorted(_table.SPACES) + ["raw"]


@functools.cache
def canonical(name: str) -> str:
    """The short (MaterialX) spelling of a colour-space name, or "raw".

    Accepts MaterialX names (also ``gamma18`` / ``gamma22`` / ``gamma24`` / ``lin_ap1``),
    USD ``Gf.ColorSpaceNames`` tokens (``lin_rec709_scene``, ...), OpenColorIO names and
    aliases of the ACES configuration, colour-science's names and UsdUVTexture's ``sRGB`` /
    ``raw``, in any letter case; unknown names raise ValueError.

    Examples
    --------
    >>> canonical("lin_ap1_scene"), canonical("sRGB"), canonical("raw"), canonical("gamma24")
    ('acescg', 'srgb_texture', 'raw', 'g24_rec709')
    >>> canonical("Utility - Linear - sRGB"), canonical("CIE XYZ-D65 - Scene-referred")
    ('lin_rec709', 'lin_ciexyzd65')
    """
    if not isinstance(name, str):
        raise TypeError(f"colour space must be a string, got {type(name).__name__}")
    key = name.strip().lower()
    hit = _table.ALIASES.get(key)
    if hit is not None:
        return hit
    if key in _table.DISPLAY:
        raise ValueError(
            f"colour space {name!r} is display-referred (an OpenColorIO display space); "
            "authored colours need a scene-referred space"
        )
    raise ValueError(
        f"colour space {name!r} is not known; known: {', '.join(known())} "
        "(and their OpenColorIO, USD *_scene and colour-science names)"
    )


@functools.cache
def _matrix(space: str) -> np.ndarray:
    m = np.array(_SPACES[space]["matrix"], dtype=np.float64)
    m.setflags(write=False)
    return m


def matrix(space: str) -> np.ndarray:
    """The 3x3 matrix from a linear ``space`` to ACEScg (rows: output channels).

    Computed by colour-science (``matrix_RGB_to_RGB``, Bradford adaptation); ValueError for
    a space with a transfer function.

    Examples
    --------
    >>> np.round(matrix("lin_rec709").sum(axis=1), 5).tolist()     # white maps to white
    [1.0, 1.0, 1.0]
    """
    space = canonical(space)
    if space == "raw" or not is_linear(space):
        raise ValueError(f"matrix: {space!r} is not a linear colour space")
    return _matrix(space).copy()


def _srgb_eotf(v: np.ndarray) -> np.ndarray:
    """The sRGB decoding of IEC 61966-2-1 (colour-science's ``eotf_sRGB``), float64."""
    with np.errstate(invalid="ignore"):
        return np.where(v <= 0.04045, v / 12.92, ((np.maximum(v, 0.04045) + 0.055) / 1.055) ** 2.4)


def decode(values: ArrayLike, space: str) -> np.ndarray:
    """Remove the transfer function of ``space`` (values keep its primaries).

    Parameters
    ----------
    values : array_like
    space : str
        A colour-space name (see ``canonical``).

    Returns
    -------
    ndarray float64 (the input's shape)

    Examples
    --------
    >>> round(float(decode([0.5, 0.5, 0.5], "srgb_texture")[0]), 5)
    0.21404
    >>> round(float(decode([0.5], "gamma22")[0]), 6) == round(0.5 ** 2.2, 6)
    True
    """
    space = canonical(space)
    v = np.asarray(values, dtype=np.float64)
    if space == "raw":
        return v.copy()
    kind = _SPACES[space]["decoding"]
    if kind[0] == "linear":
        return v.copy()
    if kind[0] == "srgb":
        return _srgb_eotf(v)
    if kind[0] == "gamma":
        return np.maximum(v, 0.0) ** kind[1]
    return np.asarray(_colour().cctf_decoding(v, function=kind[1]), dtype=np.float64).reshape(v.shape)


def to_working(rgb: ArrayLike, space: str) -> np.ndarray:
    """Convert colour(s) ``rgb`` (..., 3) from ``space`` to the working space (ACEScg).

    Parameters
    ----------
    rgb : array_like (..., 3)
    space : str
        A colour-space name (see ``canonical``); "raw" returns the values unchanged.

    Returns
    -------
    ndarray (..., 3) float64

    Examples
    --------
    >>> to_working([1.0, 1.0, 1.0], "lin_rec709").round(6).tolist()   # white stays white
    [1.0, 1.0, 1.0]
    >>> to_working([0.2, 0.4, 0.6], "acescg").tolist()
    [0.2, 0.4, 0.6]
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.shape[-1:] != (3,):
        raise ValueError(f"rgb must have shape (..., 3), got {rgb.shape}")
    space = canonical(space)
    if space in ("raw", WORKING_SPACE):
        return rgb.copy()
    return decode(rgb, space) @ _matrix(space).T


def is_linear(space: str) -> bool:
    """True when ``space`` has no transfer function (raw counts as linear).

    Examples
    --------
    >>> is_linear("lin_displayp3"), is_linear("gamma18"), is_linear("raw")
    (True, False, True)
    """
    space = canonical(space)
    return space == "raw" or _SPACES[space]["decoding"][0] == "linear"


__all__ = [
    "WORKING_SPACE",
    "WORKING_SPACE_USD",
    "canonical",
    "to_working",
    "decode",
    "matrix",
    "is_linear",
    "known",
    "build_table",
    "write_table",
    "SPECS",
]


if __name__ == "__main__":  # pragma: no cover - regenerates the table
    if "--write" in sys.argv[1:]:
        print(write_table())
    else:
        import json

        print(json.dumps(build_table(), indent=1))
