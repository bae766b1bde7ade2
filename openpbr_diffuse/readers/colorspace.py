"""Colour spaces of authored colours, converted to the one working space: ACEScg.

Every colour the readers resolve is returned in **ACEScg** (linear AP1 primaries, ACES white
point, the ``lin_ap1_scene`` of USD and ``acescg`` of MaterialX): OpenPBR's default colour
space, so OpenPBR documents in ``acescg`` pass through unchanged.  The library's nodes take the
colour as it is given (they are colour-space agnostic).

Conversions use colour-science (``colour.matrix_RGB_to_RGB`` with Bradford chromatic
adaptation, the adaptation OCIO, OpenImageIO and USD use; ``colour.cctf_decoding`` /
``colour.gamma_function`` for the encoded spaces), never hand-typed matrices.  colour-science
is imported only when a colour is not already in ACEScg (the import takes ~1-2 s).

Names accepted (MaterialX 1.39 colour-space names, USD ``Gf.ColorSpaceNames`` tokens, the
OCIO/OpenImageIO role names, UsdUVTexture ``sourceColorSpace``):
lin_rec709, srgb_texture, acescg, aces2065-1 (lin_ap0), g22_rec709, g18_rec709, g22_ap1,
srgb_ap1, lin_adobergb, adobergb, lin_displayp3, srgb_displayp3, lin_rec2020, raw/data.
"""
import functools

import numpy as np

#: The working colour space of every resolved colour (MaterialX / USD names).
WORKING_SPACE = "acescg"
WORKING_SPACE_USD = "lin_ap1_scene"

# name -> (colour-science RGB colourspace, decoding): decoding None (linear), "sRGB" (the
# sRGB piecewise curve) or a gamma exponent.  "raw" has no entry: no conversion.
_SPACES = {
    "lin_rec709": ("ITU-R BT.709", None),
    "srgb_texture": ("ITU-R BT.709", "sRGB"),
    "srgb_rec709": ("ITU-R BT.709", "sRGB"),
    "g22_rec709": ("ITU-R BT.709", 2.2),
    "g24_rec709": ("ITU-R BT.709", 2.4),
    "g18_rec709": ("ITU-R BT.709", 1.8),
    "acescg": ("ACEScg", None),
    "lin_ap1": ("ACEScg", None),
    "g22_ap1": ("ACEScg", 2.2),
    "srgb_ap1": ("ACEScg", "sRGB"),
    "aces2065-1": ("ACES2065-1", None),
    "lin_ap0": ("ACES2065-1", None),
    "lin_adobergb": ("Adobe RGB (1998)", None),
    "adobergb": ("Adobe RGB (1998)", 563.0 / 256.0),
    "g22_adobergb": ("Adobe RGB (1998)", 2.2),
    "lin_displayp3": ("Display P3", None),
    "lin_p3d65": ("Display P3", None),
    "srgb_displayp3": ("Display P3", "sRGB"),
    "srgb_p3d65": ("Display P3", "sRGB"),
    "lin_rec2020": ("ITU-R BT.2020", None),
}
_ALIASES = {
    "srgb": "srgb_texture", "linear": "lin_rec709", "lin_srgb": "lin_rec709",
    "aces": "aces2065-1", "ap1": "acescg", "ap0": "aces2065-1",
    "linear rec.709 (srgb)": "lin_rec709", "srgb encoded rec.709 (srgb)": "srgb_texture",
    "acescg ": "acescg",
}
_RAW = {"raw", "data", "identity", "none", "utility - raw"}


def canonical(name):
    """The canonical (MaterialX) spelling of a colour-space name, or "raw".

    USD names drop their ``_scene`` suffix; unknown names raise ValueError listing the known
    ones.

    Examples
    --------
    >>> canonical("lin_ap1_scene"), canonical("sRGB"), canonical("raw")
    ('acescg', 'srgb_texture', 'raw')
    """
    if not isinstance(name, str):
        raise TypeError(f"colour space must be a string, got {type(name).__name__}")
    key = name.strip().lower()
    if key.endswith("_scene"):
        key = key[: -len("_scene")]
    key = _ALIASES.get(key, key)
    if key in _RAW:
        return "raw"
    if key not in _SPACES:
        raise ValueError(f"colour space {name!r} is not known; known: {', '.join(sorted(_SPACES))}, raw")
    return key


@functools.lru_cache(maxsize=None)
def _matrix(space):
    import colour

    src = _SPACES[space][0]
    dst = _SPACES[WORKING_SPACE][0]
    return np.asarray(colour.matrix_RGB_to_RGB(colour.RGB_COLOURSPACES[src], colour.RGB_COLOURSPACES[dst],
                                               chromatic_adaptation_transform="Bradford"), dtype=np.float64)


def _decode(rgb, decoding):
    if decoding is None:
        return rgb
    import colour

    if decoding == "sRGB":
        return np.asarray(colour.cctf_decoding(rgb, function="sRGB"), dtype=np.float64)
    # a pure power law; keep the sign so negative (out-of-gamut) values stay finite
    return np.sign(rgb) * np.abs(rgb) ** decoding


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
    src, decoding = _SPACES[space]
    lin = _decode(rgb, decoding)
    if src == _SPACES[WORKING_SPACE][0]:
        return lin
    return lin @ _matrix(space).T


def decode(values, space):
    """Remove the transfer function of ``space`` (values stay in its primaries).

    Examples
    --------
    >>> round(float(decode(0.5, "srgb_texture")), 6)
    0.214041
    """
    space = canonical(space)
    v = np.asarray(values, dtype=np.float64)
    return v if space == "raw" else _decode(v, _SPACES[space][1])


def is_linear(space):
    """True when ``space`` has no transfer function (raw counts as linear)."""
    space = canonical(space)
    return space == "raw" or _SPACES[space][1] is None


__all__ = ["WORKING_SPACE", "WORKING_SPACE_USD", "canonical", "to_working", "decode", "is_linear"]
