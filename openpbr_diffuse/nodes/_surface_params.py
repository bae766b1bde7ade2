"""What every lobe of ``OpenPBRSurface`` reads: the layout of a material's parameter row, the
records its compiled functions pass, and the layer albedos the lobes share.

A surface row is a flat float64 vector of prepared parameters, built once per material by
``_surface_kernels.pack_drive``.  Its fixed part (``PARAM``, declared here) holds the
material's inputs the formulas read and values of the material alone that the per-row
formulas would otherwise recompute; ``_surface_kernels`` appends the per-lobe part (each
lobe's weight colour and score constants, sized by the lobe registry).  The lobes
(``nodes.lobes``) read their parameters at constant offsets: numba reads a global
namedtuple as constants, so ``p[at + PARAM.X_S]`` compiles to a load at a constant offset.
"""

import collections

import numpy as np

from .._jit import block
from ..microfacet import kernels as mf
from ..microfacet.tables import MU_AXIS, catmull_rom_at, node_at
from ..models.eon import eon_albedo_at
from ..models.qon import qon_albedo

#: diffuse lobe models
D_EON, D_QON, D_LAMBERT = 0, 1, 2
#: selection rules
SEL_LENGTH, SEL_MAX, SEL_UNIFORM = 0, 1, 2
#: the layer a lobe lies under (its ``LAYER``): under the dielectric specular layer, under
#: the coat (the base), under the fuzz (the coat) or on top (the fuzz)
UNDER_SPECULAR, UNDER_COAT, UNDER_FUZZ, ON_TOP = range(4)
#: the samplers of the lobes (a lobe's ``sampler``): the EON sampler (EON paper Listing 4),
#: cosine sampling, GGX (visible normals or the NDF) and the fuzz lobe's LTC
S_EON, S_COSINE, S_GGX, S_SHEEN = range(4)
N_SAMPLERS = 4
#: The floor of |wi.z| of the hemisphere samplers: the smallest normal float64.
Z_MIN = float(np.finfo(np.float64).tiny)

N_CURVE = 35  # mu nodes of the dielectric albedo table + 2 ghost nodes
N_CCURVE = 67  # mu nodes of the conductor albedo table + 2 ghost nodes


def layout(name, fields, start=0):
    """(offsets, end) of a flat layout declared as (field, width) pairs, in order, from
    ``start``: ``offsets`` is a namedtuple of each field's first index.

    Example
    -------
    >>> at, end = layout("Demo", (("A", 3), ("B", 1)))
    >>> at.B, end
    (3, 4)
    """
    offsets, here = [], start
    for _, width in fields:
        offsets.append(here)
        here += width
    return collections.namedtuple(name, [f for f, _ in fields])(*offsets), here


#: The fixed part of a surface row (float64).
PARAMS = (
    ("BASE_COLOR", 3),  # rho of the diffuse lobe
    ("R_DIFF", 1),  # base_diffuse_roughness (EON r; QON sigma)
    ("BASE_WEIGHT", 1),
    ("METAL", 1),  # base_metalness
    ("SPEC_COLOR", 3),
    ("SPEC_WEIGHT", 1),
    # the GGX layers (``_surface_kernels._pack_layer``): alpha, roughness, x, eta in this order
    ("ALPHA_S", 1),  # GGX alpha of the base specular and metal (coat-affected)
    ("R_S", 1),  # its roughness (table coordinate)
    ("X_S", 1),  # |sqrt(F0)| of the modulated index (table coordinate)
    ("ETA_S", 1),  # modulated index eta' >= 1
    ("METAL_F0", 3),  # base_weight * base_color
    ("METAL_A", 3),  # F82-tint coefficient a
    ("TRANS_W", 1),
    ("TRANS_TINT", 3),
    ("SSS_W", 1),
    ("SSS_COLOR", 3),
    ("SSS_ANISO", 1),
    ("COAT_W", 1),
    ("ALPHA_C", 1),
    ("R_C", 1),
    ("X_C", 1),
    ("ETA_C", 1),
    ("BASE_MUL", 3),  # coat attenuation x darkening of everything under the coat
    ("FUZZ_W", 1),
    ("FUZZ_COLOR", 3),
    ("FUZZ_R", 1),
    ("THIN", 1),  # geometry_thin_walled (0/1)
    # table axes fixed per material (``microfacet.tables.axis_weights``): for the base
    # specular (TAB_S) and the coat (TAB_C), the conductor table's roughness node and 4
    # weights, the dielectric table's roughness node and 4 weights, its x node and 4 weights
    ("TAB_S", 15),
    ("TAB_C", 15),
    # the dielectric table collapsed on those two axes: E_diel/E1 at every (padded) mu node,
    # for the base specular and the coat; per row only a 4-point cubic in mu remains
    ("CURVE_S", N_CURVE),
    ("CURVE_C", N_CURVE),
    # the conductor table collapsed on its roughness axis: E1, E5, E6 of the base specular's
    # roughness and E1 of the coat's at every (padded) mu node (``_conductor_curve``)
    ("E1S", N_CCURVE),
    ("E5S", N_CCURVE),
    ("E6S", N_CCURVE),
    ("E1C", N_CCURVE),
    ("R_TENTH", 1),  # base_diffuse_roughness^0.1 (the EON sampler's P_u)
    ("RHO_MS", 3),  # rho_ms(base_color, <E_F>) of the EON lobe (Eq. 18)
    ("SHEEN_FIT", 3),  # (s, m, o) of the fuzz albedo fit at fuzz_roughness
    # |K rho|^2, (K rho).(K rho_ms), |K rho_ms|^2 of the diffuse lobe (K its weight colour)
    ("DIFFUSE_SCORE", 3),
    ("EON_FIT", 3),  # (A_F, B_F, s_h) of the EON albedo at base_diffuse_roughness
    ("QON_AB", 2),  # QON's (A, B) at base_diffuse_roughness (QON diffuse, thin-walled subsurface)
)
PARAM, N_FIXED = layout("Param", PARAMS)

#: The state of mu_o that one row's lobe albedos and scores read (``state_passes`` computes it
#: for a block; ``_surface_passes.state_at`` reads one row's): the GGX basis albedos E1, E5, E6
#: and the dielectric albedo of the base specular; the coat's and the fuzz's albedos; the
#: diffuse albedo terms, E = rho e_g + rho_ms e_h; the QON albedo of the thin-walled
#: subsurface reflection (1 when not thin-walled).
LayerState = collections.namedtuple(
    "LayerState",
    (
        "e1_specular",
        "e5_specular",
        "e6_specular",
        "specular",
        "coat",
        "fuzz",
        "diffuse_g",
        "diffuse_h",
        "thin_reflection",
    ),
)

#: The two directions of a row in the local frame (normal +z): wi and wo.
Directions = collections.namedtuple("Directions", ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z"))

#: What a lobe's ``eval`` reads besides the parameters and the directions: the diffuse model,
#: multiple scattering on, the base specular's GGX reflection without Fresnel and its wo.h
#: (computed once a row, shared by the specular and metal lobes), the GGX albedo E1 of the
#: base specular and of the coat (multiple-scattering factors, the transmission's
#: normalisation) and the fuzz albedo.
EvalInputs = collections.namedtuple(
    "EvalInputs", ("dmodel", "multiscatter", "ggx_f", "ggx_cos", "e1_specular", "e1_coat", "e_fuzz")
)


@block
def ggx_reflection(d, alpha):
    """(f, wo.h): the GGX reflection at alpha of ``Directions`` d without Fresnel
    (``microfacet.kernels.reflection``)."""
    return mf.reflection(d.wi_x, d.wi_y, d.wi_z, d.wo_x, d.wo_y, d.wo_z, alpha)


@block
def ggx_reflection_pdf(d, alpha, vndf):
    """The pdf of the GGX reflection sampler at alpha (``microfacet.kernels.reflection_pdf``)
    producing the wi of ``Directions`` d."""
    return mf.reflection_pdf(d.wi_x, d.wi_y, d.wi_z, d.wo_x, d.wo_y, d.wo_z, alpha, vndf)


@block
def mirrored(d):
    """``Directions`` d with wi mirrored through the surface (wi.z negated)."""
    return Directions(d.wi_x, d.wi_y, -d.wi_z, d.wo_x, d.wo_y, d.wo_z)


@block
def cubic_at(p, b, w0, w1, w2, w3):
    return w0 * p[b] + w1 * p[b + 1] + w2 * p[b + 2] + w3 * p[b + 3]


@block
def layer_albedos(p, offset, e1, e5, e6, ratio, mu, x, ms):
    """(E1, E5, E6, E) of a GGX layer from its curves collapsed per material: the conductor
    basis at p[offset + e1], p[offset + e5], p[offset + e6] (PARAM.E*), the dielectric ratio at p[offset + ratio]
    (PARAM.CURVE_*): the basis albedos and the dielectric lobe's albedo with the
    multiple-scattering factor (0 at x = 0: index-matched)."""
    im, tm = node_at(mu, N_CCURVE - 2, MU_AXIS)
    w0, w1, w2, w3 = catmull_rom_at(tm)
    E1 = min(max(cubic_at(p, offset + e1 + im, w0, w1, w2, w3), 0.0), 1.0)
    E5 = max(cubic_at(p, offset + e5 + im, w0, w1, w2, w3), 0.0)
    E6 = max(cubic_at(p, offset + e6 + im, w0, w1, w2, w3), 0.0)
    im, tm = node_at(mu, N_CURVE - 2, MU_AXIS)
    w0, w1, w2, w3 = catmull_rom_at(tm)
    E = min(max(cubic_at(p, offset + ratio + im, w0, w1, w2, w3), 0.0), 1.0) * E1
    E = E if x > 0.0 else 0.0  # a select: a loop over rows calling this stays branch-free
    return E1, E5, E6, E * mf.multiscatter(x * x, E1, ms)


@block
def diffuse_albedo_terms(dmodel, p, offset, mu):
    """(e_g, e_h) of the diffuse lobe's albedo rho e_g + m(rho) e_h (channel-free): EON
    Eq. 20 (m = rho_ms), QON Eq. 8 or Lambert (m = 0), from the material's fits (PARAM.EON_FIT,
    PARAM.QON_AB)."""
    if dmodel == D_EON:
        return eon_albedo_at(
            mu, p[offset + PARAM.EON_FIT], p[offset + PARAM.EON_FIT + 1], p[offset + PARAM.EON_FIT + 2]
        )
    if dmodel == D_QON:
        return qon_albedo(mu, p[offset + PARAM.QON_AB], p[offset + PARAM.QON_AB + 1]), 0.0
    return 1.0, 0.0
