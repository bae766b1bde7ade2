"""Colour spaces of authored colours, converted to the one working space: ACEScg.

Every colour the readers resolve is returned in **ACEScg** (linear AP1 primaries, ACES white
point; ``lin_ap1_scene`` in USD, ``acescg`` in MaterialX): OpenPBR's default colour space, so
OpenPBR documents in ``acescg`` pass through unchanged.  The library's nodes take the colour
as it is given (they are colour-space agnostic).

Conversions use OpenImageIO's OpenColorIO configuration (its built-in CG config, which knows
the MaterialX names -- lin_rec709, srgb_texture, acescg, ... -- and USD's ``*_scene`` names
as aliases), never hand-typed matrices: a linear space's 3x3 matrix to ACEScg is obtained once
by converting the unit primaries with ``ImageBufAlgo.colorconvert`` and cached; encoded spaces
(sRGB, gamma) are converted value by value with the same call.  OpenImageIO imports in
~0.1 s, where colour-science takes 1-2 s, which matters when thousands of materials are read.
"""

import functools

import numpy as np

#: The working colour space of every resolved colour (MaterialX / USD names).
WORKING_SPACE = "acescg"
WORKING_SPACE_USD = "lin_ap1_scene"

# short (MaterialX) name -> OpenColorIO colour space of OpenImageIO's built-in config
_OCIO = {
    "lin_rec709": "Linear Rec.709 (sRGB)",
    "srgb_texture": "sRGB Encoded Rec.709 (sRGB)",
    "g22_rec709": "Gamma 2.2 Encoded Rec.709",
    "g18_rec709": "Gamma 1.8 Encoded Rec.709",
    "g24_rec709": "Gamma 2.4 Encoded Rec.709",
    "acescg": "ACEScg",
    "aces2065-1": "ACES2065-1",
    "g22_ap1": "Gamma 2.2 Encoded AP1",
    "srgb_ap1": "sRGB Encoded AP1",
    "lin_adobergb": "Linear AdobeRGB",
    "adobergb": "Gamma 2.2 Encoded AdobeRGB",
    "lin_displayp3": "Linear P3-D65",
    "srgb_displayp3": "sRGB Encoded P3-D65",
    "lin_rec2020": "Linear Rec.2020",
}
_SHORT = {v: k for k, v in _OCIO.items()}
# encoded space -> the linear space with the same primaries (what ``decode`` returns)
_LINEAR_OF = {
    "srgb_texture": "lin_rec709",
    "g22_rec709": "lin_rec709",
    "g18_rec709": "lin_rec709",
    "g24_rec709": "lin_rec709",
    "g22_ap1": "acescg",
    "srgb_ap1": "acescg",
    "adobergb": "lin_adobergb",
    "srgb_displayp3": "lin_displayp3",
}
_RAW = {"raw", "data", "identity", "none", "utility - raw", ""}


@functools.lru_cache(maxsize=1)
def _config():
    import OpenImageIO as oiio

    return oiio.ColorConfig()


@functools.cache
def canonical(name):
    """The short (MaterialX) spelling of a colour-space name, or "raw".

    Accepts MaterialX names, USD ``Gf.ColorSpaceNames`` tokens (``lin_rec709_scene``, ...),
    OpenColorIO names and UsdUVTexture's ``sRGB`` / ``raw``; unknown names raise ValueError.

    Examples
    --------
    >>> canonical("lin_ap1_scene"), canonical("sRGB"), canonical("raw")
    ('acescg', 'srgb_texture', 'raw')
    """
    if not isinstance(name, str):
        raise TypeError(f"colour space must be a string, got {type(name).__name__}")
    key = name.strip()
    if key.lower() in _RAW:
        return "raw"
    if key.lower() in _OCIO:
        return key.lower()
    if key.lower() == "srgb":
        return "srgb_texture"
    resolved = _config().resolve(key)
    if resolved in _SHORT:
        return _SHORT[resolved]
    if _config().isData(resolved) if resolved in _config().getColorSpaceNames() else False:
        return "raw"
    raise ValueError(
        f"colour space {name!r} is not known; known: {', '.join(sorted(_OCIO))}, raw "
        "(and their USD *_scene / OpenColorIO names)"
    )


def _convert(values, src, dst):
    """OpenImageIO colorconvert of values (n, 3) from OCIO space src to dst (float64 out)."""
    import OpenImageIO as oiio

    a = np.ascontiguousarray(np.asarray(values, dtype=np.float32).reshape(-1, 1, 3))
    out = oiio.ImageBufAlgo.colorconvert(oiio.ImageBuf(a), src, dst)
    if out.has_error:
        raise ValueError(f"colour conversion {src} -> {dst} failed: {out.geterror()}")
    return np.asarray(out.get_pixels(oiio.FLOAT), dtype=np.float64).reshape(-1, 3)


@functools.cache
def matrix(space):
    """The 3x3 matrix from a linear ``space`` to ACEScg (rows: output channels).

    Obtained from OpenColorIO by converting the unit primaries.

    Examples
    --------
    >>> np.round(matrix("lin_rec709").sum(axis=1), 5).tolist()     # white maps to white
    [1.0, 1.0, 1.0]
    """
    space = canonical(space)
    if space not in _OCIO or space in _LINEAR_OF:
        raise ValueError(f"matrix: {space!r} is not a linear colour space")
    return _convert(np.eye(3), _OCIO[space], _OCIO[WORKING_SPACE]).T


def to_working(rgb, space):
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
    if space in _SRGB_CURVE:
        return _srgb_eotf(rgb) @ matrix(_LINEAR_OF[space]).T
    if space in _LINEAR_OF:
        return _convert(rgb, _OCIO[space], _OCIO[WORKING_SPACE]).reshape(rgb.shape)
    return rgb @ matrix(space).T


def decode(values, space):
    """Remove the transfer function of ``space`` (values keep its primaries).

    Examples
    --------
    >>> round(float(decode([0.5, 0.5, 0.5], "srgb_texture")[0]), 5)
    0.21404
    """
    space = canonical(space)
    v = np.asarray(values, dtype=np.float64)
    if space not in _LINEAR_OF:
        return v.copy()
    if space in _SRGB_CURVE:
        return _srgb_eotf(v)
    return _convert(v, _OCIO[space], _OCIO[_LINEAR_OF[space]]).reshape(v.shape)


#: Spaces whose transfer function is the sRGB piecewise curve: decoded in closed form in
#: double precision (OpenColorIO's CPU processor approximates the power, 1.0 -> 1.000024,
#: which would read white as out of range).
_SRGB_CURVE = ("srgb_texture", "srgb_ap1", "srgb_displayp3")


def _srgb_eotf(v):
    """The sRGB decoding of IEC 61966-2-1 (odd-symmetric below 0), float64."""
    a = np.abs(v)
    lin = np.where(a <= 0.04045, a / 12.92, ((a + 0.055) / 1.055) ** 2.4)
    return np.sign(v) * lin


def is_linear(space):
    """True when ``space`` has no transfer function (raw counts as linear)."""
    return canonical(space) not in _LINEAR_OF


__all__ = ["WORKING_SPACE", "WORKING_SPACE_USD", "canonical", "to_working", "decode", "matrix", "is_linear"]
