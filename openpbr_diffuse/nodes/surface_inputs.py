"""The inputs of ``OpenPBRSurface``, declared once: the MaterialX nodedef
``ND_open_pbr_surface_surfaceshader`` gives each input's name, type, default and range
(``materialx_defs``), and ``MODELLING`` says how the model uses it.  Everything else is
derived from these two: the inputs the compiled lobes read and their packed row
(``packed_inputs``, in ``MODELLING`` order, widths from the nodedef types), the inputs the
model uses (``MODELLED``) and the ones reported with a warning when set (every other input).

Example
-------
>>> "transmission_depth" in MODELLED, "thin_film_weight" in MODELLED
(True, False)
>>> packed_inputs()[:2]
(('base_weight', 1), ('base_color', 3))
"""

import functools

NODEDEF = "ND_open_pbr_surface_surfaceshader"

#: how a modelled input is used: read by the compiled lobes (packed into the material's row),
#: or the shading frame (the directions' transform)
PACKED, FRAME = "packed", "frame"

#: (input, how it is modelled, what it does): every input the model uses, once.  An input of
#: the nodedef not listed here has no effect and is reported (``IgnoredInputWarning``).
MODELLING = (
    ("base_weight", PACKED, "diffuse weight; metal F0 scale"),
    ("base_color", PACKED, "diffuse rho; metal F0"),
    ("base_diffuse_roughness", PACKED, "EON r / QON sigma"),
    ("base_metalness", PACKED, "metal / dielectric mix"),
    ("specular_weight", PACKED, "modulated F0 of the specular; metal weight"),
    ("specular_color", PACKED, "specular tint; metal F82 tint"),
    ("specular_roughness", PACKED, "GGX roughness of the specular and metal"),
    ("specular_ior", PACKED, "specular index"),
    ("transmission_weight", PACKED, "transmission weight"),
    ("transmission_color", PACKED, "transmission tint"),
    ("transmission_depth", PACKED, "> 0 switches the transmission tint off, as the reference graph"),
    ("subsurface_weight", PACKED, "subsurface weight"),
    ("subsurface_color", PACKED, "subsurface albedo"),
    ("subsurface_scatter_anisotropy", PACKED, "thin-walled reflection / translucency split"),
    ("coat_weight", PACKED, "coat weight"),
    ("coat_color", PACKED, "coat attenuation of the base"),
    ("coat_roughness", PACKED, "coat GGX roughness; the base specular's under the coat"),
    ("coat_ior", PACKED, "coat index; the base specular's under the coat"),
    ("coat_darkening", PACKED, "base darkening under the coat"),
    ("fuzz_weight", PACKED, "fuzz weight"),
    ("fuzz_color", PACKED, "fuzz tint"),
    ("fuzz_roughness", PACKED, "sheen roughness"),
    ("geometry_thin_walled", PACKED, "thin-walled subsurface"),
    ("geometry_normal", FRAME, "shading normal: directions are world-space"),
)

#: the inputs the model uses, in ``MODELLING`` order
MODELLED = tuple(name for name, _, _ in MODELLING)

#: the width of a packed input of each nodedef type
_WIDTHS = {"float": 1, "boolean": 1, "integer": 1, "color3": 3, "vector3": 3}


@functools.cache
def packed_inputs(lobe_inputs=()):
    """((input, width), ...) of the packed inputs in ``MODELLING`` order, then the inputs
    registered lobes read as they are (``lobe_inputs``), widths from the nodedef's types:
    the row ``_surface_kernels.pack_drive`` reads.

    Raises
    ------
    ValueError
        A name of ``lobe_inputs`` is not an input of the nodedef, or already modelled.
    """
    from .materialx_defs import nodedef_inputs

    defs = nodedef_inputs(NODEDEF)
    for name in lobe_inputs:
        if name not in defs or name in MODELLED:
            raise ValueError(f"lobe_inputs: {name!r} is not an unmodelled input of {NODEDEF}")
    names = [name for name, how, _ in MODELLING if how == PACKED] + list(lobe_inputs)
    return tuple((name, _WIDTHS[defs[name].type]) for name in names)
