"""The lobes of ``OpenPBRSurface`` as scalar compiled functions, and the packing of a
material's inputs into its parameter vector.

Lobes are plain values with the verbs of pbrt-v4's ``BxDF`` -- ``lobe_f`` (the lobe's own
BSDF, weight not applied), ``lobe_sample`` and ``lobe_pdf`` -- selected by a lobe id, with
``lobe_albedo`` (its directional albedo E_k(wo)), ``layer_factor`` and ``lobe_score`` (its
selection score |w_k E_k|).  A surface row is a flat vector of prepared parameters (layout
``PARAMS``, built once per material by ``pack_drive``).  Each weight is a layer factor of mu_o
(the albedos of the specular, coat and fuzz layers, which scale what lies beneath) times a
colour of the material, w_k[c] = L_k(mu_o) K_k[c] (``layer_factor``, ``_pack_weights``), so
that the selection scores are constants of the material times functions of mu_o.  No input
is checked here: the public class checks its inputs once, at construction and on each
call's directions.

The batch drivers (``_surface_drivers``) call these one lobe at a time over blocks of rows
(``_surface_passes``), with the lobe id a constant: each kernel folds to one lobe's formula,
and the kernels branch on directions only through selects, so the loops vectorise.

Lobe ids (slots): DIFFUSE, SPECULAR, METAL, TRANSMISSION, SUBSURFACE (the thin-walled
reflection part when thin-walled), SUBSURFACE_T (thin-walled translucency), COAT, FUZZ.
"""

import collections
import math

import numpy as np

from .._jit import INV_PI, block, by_constant, opaque, pointer_of, serial
from ..microfacet import fresnel
from ..microfacet import kernels as mf
from ..microfacet.sheen import sheen_albedo_fit, sheen_density, sheen_sample
from ..microfacet.tables import MU_AXIS, R_AXIS, X_AXIS, catmull_rom_at, node_at
from ..models.eon import eon_albedo_at, eon_albedo_fit, eon_terms, rho_ms
from ..models.fon import E_F_avg
from ..models.qon import qon_AB, qon_albedo, qon_terms
from ..sampling.ltc import from_frame, ltc_frame, to_frame
from ..sampling.mis import eon_pdf, eon_sample, pow_tenth
from ..sampling.simple import cosine_pdf, cosine_sample_local

DIFFUSE, SPECULAR, METAL, TRANSMISSION, SUBSURFACE, SUBSURFACE_T, COAT, FUZZ = range(8)
N_LOBES = 8
LOBE_NAMES = ("diffuse", "specular", "metal", "transmission", "subsurface", "subsurface_transmission", "coat", "fuzz")
#: diffuse lobe models
D_EON, D_QON, D_LAMBERT = 0, 1, 2
#: selection rules
SEL_LENGTH, SEL_MAX, SEL_UNIFORM = 0, 1, 2

N_CURVE = 35  # mu nodes of the dielectric albedo table + 2 ghost nodes
N_CCURVE = 67  # mu nodes of the conductor albedo table + 2 ghost nodes


def layout(name, fields):
    """(offsets, size) of a flat layout declared as (field, width) pairs, in order: ``offsets``
    is a namedtuple of each field's first index.  numba reads a global namedtuple as
    constants, so ``p[o + PARAM.X_S]`` compiles to a load at a constant offset."""
    offsets, at = [], 0
    for _, width in fields:
        offsets.append(at)
        at += width
    return collections.namedtuple(name, [f for f, _ in fields])(*offsets), at


#: The parameter layout of one surface row (float64), built once per material by
#: ``pack_drive``: the material's inputs the formulas read, and values of the material alone
#: that the per-row formulas would otherwise recompute.
PARAMS = (
    ("BASE_COLOR", 3),  # rho of the diffuse lobe
    ("R_DIFF", 1),  # base_diffuse_roughness (EON r; QON sigma)
    ("BASE_WEIGHT", 1),
    ("METAL", 1),  # base_metalness
    ("SPEC_COLOR", 3),
    ("SPEC_WEIGHT", 1),
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
    # every lobe's weight is a layer factor of mu_o times a constant of the material,
    # w_k[c](wo) = L_k(wo) K_k[c] (``layer_factor``); the selection scores |w_k E_k| then
    # reduce to constants of the material times functions of mu_o (``lobe_score``)
    ("K", 3 * N_LOBES),  # K_k[c]
    # |K_k e_k| and max_c |K_k[c] e_k[c]| for the lobes whose albedo is a constant colour e_k
    # or a scalar times 1 (e_k = 1)
    ("SC", 2 * N_LOBES),
    ("DQ", 3),  # |K rho|^2, (K rho).(K rho_ms), |K rho_ms|^2 of the diffuse lobe
    ("EON_FIT", 3),  # (A_F, B_F, s_h) of the EON albedo at base_diffuse_roughness
    ("QON_AB", 2),  # QON's (A, B) at base_diffuse_roughness (QON diffuse, thin-walled subsurface)
)
PARAM, N_PARAMS = layout("Param", PARAMS)
# module-level names of the offsets the table-lookup tests pass to ``layer_albedos``
P_X_S, P_X_C, P_CURVE_S, P_CURVE_C = PARAM.X_S, PARAM.X_C, PARAM.CURVE_S, PARAM.CURVE_C
P_E1S, P_E5S, P_E6S, P_E1C = PARAM.E1S, PARAM.E5S, PARAM.E6S, PARAM.E1C


# --------------------------------------------------------------------------- packing
# The material's inputs, in this order (float64; colours 3 wide), are packed into the
# parameter layout above by ``pack_drive``, once per material.
RAW = (
    ("base_color", 3),
    ("base_diffuse_roughness", 1),
    ("base_weight", 1),
    ("base_metalness", 1),
    ("specular_color", 3),
    ("specular_weight", 1),
    ("specular_roughness", 1),
    ("specular_ior", 1),
    ("transmission_weight", 1),
    ("transmission_color", 3),
    ("transmission_depth", 1),
    ("subsurface_weight", 1),
    ("subsurface_color", 3),
    ("subsurface_scatter_anisotropy", 1),
    ("coat_weight", 1),
    ("coat_color", 3),
    ("coat_roughness", 1),
    ("coat_ior", 1),
    ("coat_darkening", 1),
    ("fuzz_weight", 1),
    ("fuzz_color", 3),
    ("fuzz_roughness", 1),
    ("geometry_thin_walled", 1),
)
INPUT, N_RAW = layout("Input", RAW)
#: warning bits of ``pack_drive``
W_SPEC_TIR, W_COAT_TIR, W_F82_NEGATIVE = 1, 2, 4


@block
def _axes(out, q, v, n, kind):
    """Node index and Catmull-Rom weights of v on a table axis, into out[q:q + 5]."""
    i, t = node_at(v, n, kind)
    w0, w1, w2, w3 = catmull_rom_at(t)
    out[q] = i
    out[q + 1] = w0
    out[q + 2] = w1
    out[q + 3] = w2
    out[q + 4] = w3


@block
def _table_axes(out, q, r, x, nCr, nRr, nRx):
    _axes(out, q, r, nCr, R_AXIS)
    _axes(out, q + 5, r, nRr, R_AXIS)
    _axes(out, q + 10, x, nRx, X_AXIS)


@block
def _curve(out, q, t, R):
    """out[q + m] = the dielectric ratio table at the (roughness, x) of the axes at out[t:]
    for every padded mu node m (the same tensor-product Catmull-Rom, summed over two axes)."""
    ir, ix = int(out[t + 5]), int(out[t + 10])
    for m in range(N_CURVE):
        v = 0.0
        for a in range(4):
            for b in range(4):
                v += out[t + 6 + a] * out[t + 11 + b] * R[ir + a, ix + b, m]
        out[q + m] = v


@block
def _conductor_curve(out, q, t, C, c):
    """out[q + m] = basis albedo c of the conductor table at the roughness whose node and
    weights are out[t:t + 5], for every padded mu node m."""
    ir = int(out[t])
    for m in range(N_CCURVE):
        out[q + m] = (
            out[t + 1] * C[ir, m, c]
            + out[t + 2] * C[ir + 1, m, c]
            + out[t + 3] * C[ir + 2, m, c]
            + out[t + 4] * C[ir + 3, m, c]
        )


@block
def _pack_weights(out, o):
    """The material part K_k[c] of every lobe's weight (PARAM.K), following the reference graph
    (open_pbr_surface.mtlx): the base attenuated by the coat (PARAM.BASE_MUL); metal /
    dielectric by base_metalness; under the dielectric specular layer the substrate mixes
    transmission, subsurface and diffuse; the subsurface lobe is Lambert, or when thin-walled
    the reflection half of the thin-walled mix (QON, colour^2 (1 - g)/2) and SUBSURFACE_T its
    translucent half.  Then the score constants (PARAM.SC, PARAM.DQ) of ``lobe_score``."""
    M, T, S, g = out[o + PARAM.METAL], out[o + PARAM.TRANS_W], out[o + PARAM.SSS_W], out[o + PARAM.SSS_ANISO]
    thin = out[o + PARAM.THIN] > 0.0
    for c in range(3):
        base = out[o + PARAM.BASE_MUL + c]
        diel = base * (1.0 - M)
        solid = diel * (1.0 - T)  # neither metal nor transmission
        color = out[o + PARAM.SSS_COLOR + c]
        K = (
            solid * (1.0 - S) * out[o + PARAM.BASE_WEIGHT],  # DIFFUSE
            diel * out[o + PARAM.SPEC_COLOR + c],  # SPECULAR
            base * M * out[o + PARAM.SPEC_WEIGHT],  # METAL
            diel * T,  # TRANSMISSION
            solid * S * 0.5 * color * (1.0 - g) if thin else solid * S,  # SUBSURFACE
            solid * S * 0.5 * color * (1.0 + g),  # SUBSURFACE_T
            out[o + PARAM.COAT_W],  # COAT
            out[o + PARAM.FUZZ_W] * out[o + PARAM.FUZZ_COLOR + c],
        )  # FUZZ
        for k in range(N_LOBES):
            out[o + PARAM.K + 3 * k + c] = K[k]
    for k in range(N_LOBES):
        n2 = 0.0
        mx = 0.0
        for c in range(3):
            e = 1.0  # SPECULAR, COAT, FUZZ (scalar albedos), and DIFFUSE, METAL (unused)
            if k == TRANSMISSION:
                e = out[o + PARAM.TRANS_TINT + c]
            elif k == SUBSURFACE or k == SUBSURFACE_T:
                e = out[o + PARAM.SSS_COLOR + c]
            v = out[o + PARAM.K + 3 * k + c] * e
            n2 += v * v
            mx = max(mx, abs(v))
        out[o + PARAM.SC + 2 * k] = math.sqrt(n2)
        out[o + PARAM.SC + 2 * k + 1] = mx
    a = b = d = 0.0
    for c in range(3):
        x = out[o + PARAM.K + c] * out[o + PARAM.BASE_COLOR + c]
        y = out[o + PARAM.K + c] * out[o + PARAM.RHO_MS + c]
        a += x * x
        b += x * y
        d += y * y
    out[o + PARAM.DQ], out[o + PARAM.DQ + 1], out[o + PARAM.DQ + 2] = a, b, d


def _pack_drive(raw_rows, out_rows, CT, RT):
    """Pack rows of RAW inputs into parameter rows (the reference graph's derived values);
    returns (mask of the lobes active in some row, warning bits).  Both row buffers are
    indexed through their data pointers (``_jit.pointer_of``: cheaper to compile)."""
    m = raw_rows.shape[0] // N_RAW
    raw, out = pointer_of(raw_rows), pointer_of(out_rows)
    mask = 0
    warn = 0
    nCr, nRr, nRx = CT.shape[0] - 2, RT.shape[0] - 2, RT.shape[1] - 2
    for i in range(m):
        a = i * N_RAW
        o = i * N_PARAMS
        bw, M, sw = raw[a + INPUT.base_weight], raw[a + INPUT.base_metalness], raw[a + INPUT.specular_weight]
        r_s, ior = raw[a + INPUT.specular_roughness], raw[a + INPUT.specular_ior]
        T, S, g = (
            raw[a + INPUT.transmission_weight],
            raw[a + INPUT.subsurface_weight],
            raw[a + INPUT.subsurface_scatter_anisotropy],
        )
        C, r_c, c_ior, c_dark = (
            raw[a + INPUT.coat_weight],
            raw[a + INPUT.coat_roughness],
            raw[a + INPUT.coat_ior],
            raw[a + INPUT.coat_darkening],
        )
        F, thin = raw[a + INPUT.fuzz_weight], raw[a + INPUT.geometry_thin_walled]
        # the coat's effect on the base specular [effective_specular_roughness, eta_s]
        r_eff = (1.0 - C) * r_s + C * min(1.0, 2.0 * r_c**4 + r_s**4) ** 0.25
        eta_s = ior
        if C > 0.0:
            ratio = ior / c_ior
            eta_s = (1.0 - C) * ior + C * (ratio if ratio > 1.0 else 1.0 / ratio)
        x = fresnel.modulated_x(sw, eta_s)
        if x < 0.0:
            warn |= W_SPEC_TIR
        x = abs(x)
        xc = fresnel.modulated_x(1.0, c_ior)
        if xc < 0.0 and C > 0.0:
            warn |= W_COAT_TIR
        xc = abs(xc)
        K = 1.0 - (1.0 - fresnel.f0(c_ior)) / (c_ior * c_ior)
        for c in range(3):
            bc = raw[a + INPUT.base_color + c]
            sc = raw[a + INPUT.specular_color + c]
            out[o + PARAM.BASE_COLOR + c] = bc
            out[o + PARAM.SPEC_COLOR + c] = sc
            F0 = bw * bc
            out[o + PARAM.METAL_F0 + c] = F0
            am = fresnel.f82_a(F0, sc)
            out[o + PARAM.METAL_A + c] = am
            if M > 0.0 and sw > 0.0:
                for k in range(257):
                    if fresnel.f82(k / 256.0, F0, am) < 0.0:
                        warn |= W_F82_NEGATIVE
            out[o + PARAM.TRANS_TINT + c] = (
                1.0 if raw[a + INPUT.transmission_depth] > 0.0 else raw[a + INPUT.transmission_color + c]
            )
            ssc = raw[a + INPUT.subsurface_color + c]
            out[o + PARAM.SSS_COLOR + c] = ssc
            # base darkening and coat attenuation [Kcoat, Ebase, base_darkening, coat_attenuation]
            E_base = (1.0 - M) * ((1.0 - S) * bc + S * ssc) + M * bc * sw
            dark = (1.0 - K) / (1.0 - E_base * K)
            out[o + PARAM.BASE_MUL + c] = (1.0 + C * c_dark * (dark - 1.0)) * (
                1.0 + C * (raw[a + INPUT.coat_color + c] - 1.0)
            )
            out[o + PARAM.FUZZ_COLOR + c] = raw[a + INPUT.fuzz_color + c]
        out[o + PARAM.R_DIFF] = raw[a + INPUT.base_diffuse_roughness]
        out[o + PARAM.R_TENTH] = pow_tenth(raw[a + INPUT.base_diffuse_roughness])
        avg = E_F_avg(raw[a + INPUT.base_diffuse_roughness])
        for c in range(3):
            out[o + PARAM.RHO_MS + c] = rho_ms(raw[a + INPUT.base_color + c], avg)
        out[o + PARAM.SHEEN_FIT], out[o + PARAM.SHEEN_FIT + 1], out[o + PARAM.SHEEN_FIT + 2] = sheen_albedo_fit(
            raw[a + INPUT.fuzz_roughness]
        )
        out[o + PARAM.EON_FIT], out[o + PARAM.EON_FIT + 1], out[o + PARAM.EON_FIT + 2] = eon_albedo_fit(
            raw[a + INPUT.base_diffuse_roughness]
        )
        out[o + PARAM.QON_AB], out[o + PARAM.QON_AB + 1] = qon_AB(raw[a + INPUT.base_diffuse_roughness], 0.33)
        out[o + PARAM.BASE_WEIGHT] = bw
        out[o + PARAM.METAL] = M
        out[o + PARAM.SPEC_WEIGHT] = sw
        out[o + PARAM.ALPHA_S] = mf.alpha_of(r_eff)
        out[o + PARAM.R_S] = r_eff
        out[o + PARAM.X_S] = x
        out[o + PARAM.ETA_S] = fresnel.eta_of_x(x)
        out[o + PARAM.TRANS_W] = T
        out[o + PARAM.SSS_W] = S
        out[o + PARAM.SSS_ANISO] = g
        out[o + PARAM.COAT_W] = C
        out[o + PARAM.ALPHA_C] = mf.alpha_of(r_c)
        out[o + PARAM.R_C] = r_c
        out[o + PARAM.X_C] = xc
        out[o + PARAM.ETA_C] = fresnel.eta_of_x(xc)
        out[o + PARAM.FUZZ_W] = F
        out[o + PARAM.FUZZ_R] = raw[a + INPUT.fuzz_roughness]
        out[o + PARAM.THIN] = thin
        _table_axes(out, o + PARAM.TAB_S, r_eff, x, nCr, nRr, nRx)
        _table_axes(out, o + PARAM.TAB_C, r_c, xc, nCr, nRr, nRx)
        _curve(out, o + PARAM.CURVE_S, o + PARAM.TAB_S, RT)
        _curve(out, o + PARAM.CURVE_C, o + PARAM.TAB_C, RT)
        _conductor_curve(out, o + PARAM.E1S, o + PARAM.TAB_S, CT, opaque(0))
        _conductor_curve(out, o + PARAM.E5S, o + PARAM.TAB_S, CT, opaque(1))
        _conductor_curve(out, o + PARAM.E6S, o + PARAM.TAB_S, CT, opaque(2))
        _conductor_curve(out, o + PARAM.E1C, o + PARAM.TAB_C, CT, opaque(0))
        _pack_weights(out, o)
        # lobes that can be non-zero
        diel = 1.0 - M
        sc_any = (
            raw[a + INPUT.specular_color] > 0.0
            or raw[a + INPUT.specular_color + 1] > 0.0
            or raw[a + INPUT.specular_color + 2] > 0.0
        )
        on = (
            diel * (1.0 - T) * (1.0 - S) * bw > 0.0,
            diel > 0.0 and x > 0.0 and sc_any,
            M > 0.0 and sw > 0.0,
            diel * T > 0.0,
            diel * (1.0 - T) * S > 0.0,
            thin > 0.0 and diel * (1.0 - T) * S > 0.0,
            C > 0.0,
            F > 0.0,
        )
        for k in range(N_LOBES):
            if on[k]:
                mask |= 1 << k
    return mask, warn


pack_drive = serial(_pack_drive)


@block
def cubic_at(p, b, w0, w1, w2, w3):
    return w0 * p[b] + w1 * p[b + 1] + w2 * p[b + 2] + w3 * p[b + 3]


@block
def layer_albedos(p, o, e1, e5, e6, q, mu, x, ms):
    """(E1, E5, E6, E) of a GGX layer from its curves collapsed per material: the conductor
    basis at p[o + e1], p[o + e5], p[o + e6] (PARAM.E*), the dielectric ratio at p[o + q]
    (PARAM.CURVE_*): the basis albedos and the dielectric lobe's albedo with the
    multiple-scattering factor (0 at x = 0: index-matched)."""
    im, tm = node_at(mu, N_CCURVE - 2, MU_AXIS)
    w0, w1, w2, w3 = catmull_rom_at(tm)
    E1 = min(max(cubic_at(p, o + e1 + im, w0, w1, w2, w3), 0.0), 1.0)
    E5 = max(cubic_at(p, o + e5 + im, w0, w1, w2, w3), 0.0)
    E6 = max(cubic_at(p, o + e6 + im, w0, w1, w2, w3), 0.0)
    im, tm = node_at(mu, N_CURVE - 2, MU_AXIS)
    w0, w1, w2, w3 = catmull_rom_at(tm)
    E = min(max(cubic_at(p, o + q + im, w0, w1, w2, w3), 0.0), 1.0) * E1
    E = E if x > 0.0 else 0.0  # a select: a loop over rows calling this stays branch-free
    return E1, E5, E6, E * mf.multiscatter(x * x, E1, ms)


@block
def diffuse_albedo_terms(dmodel, p, o, mu):
    """(e_g, e_h) of the diffuse lobe's albedo rho e_g + m(rho) e_h (channel-free): EON
    Eq. 20 (m = rho_ms), QON Eq. 8 or Lambert (m = 0), from the material's fits (PARAM.EON_FIT,
    PARAM.QON_AB)."""
    if dmodel == D_EON:
        return eon_albedo_at(mu, p[o + PARAM.EON_FIT], p[o + PARAM.EON_FIT + 1], p[o + PARAM.EON_FIT + 2])
    if dmodel == D_QON:
        return qon_albedo(mu, p[o + PARAM.QON_AB], p[o + PARAM.QON_AB + 1]), 0.0
    return 1.0, 0.0


@block
def diffuse_albedo(dmodel, rho, rms, eg, eh):
    """One channel of the diffuse albedo from ``diffuse_albedo_terms``; rms = rho_ms(rho)."""
    if dmodel == D_EON:
        return rho * eg + rms * eh
    return rho * eg


@block
def metal_albedo(p, o, c, E1, E5, E6, ms):
    """F82-tint GGX albedo F0 (E1 - E5) + E5 - a E6 (times the multiple-scattering factor)."""
    F0 = p[o + PARAM.METAL_F0 + c]
    return (F0 * (E1 - E5) + E5 - p[o + PARAM.METAL_A + c] * E6) * mf.multiscatter(F0, E1, ms)


@block
def layer_factor(k, Tu, Tb, Tf):
    """L_k, the part of lobe k's weight that depends on wo: w_k[c] = L_k K_k[c].

    Each layer passes 1 - weight E_layer(mu_o) of what lies beneath (albedo scaling): fuzz
    (Tf = 1 - F E_fuzz) over coat (Tb = Tf (1 - C E_coat)) over the base, and the dielectric
    specular layer (Tu = Tb (1 - E_spec)) over transmission, subsurface and diffuse
    (``_pack_weights`` holds the material part K_k)."""
    if k == FUZZ:
        return 1.0
    if k == COAT:
        return Tf
    if k == SPECULAR or k == METAL:
        return Tb
    return Tu


#: The state of mu_o that one row's lobe albedos and scores read (``state_passes`` computes it
#: for a block; ``_surface_passes.state_at`` reads one row's): E1s, E5s, E6s, Es -- the GGX
#: basis albedos E1, E5, E6 and the dielectric albedo of the base specular; Ec, Ef -- the coat's
#: and the fuzz's albedos; eg, eh -- the diffuse albedo terms, E = rho e_g + rho_ms e_h; Eq --
#: the QON albedo of the thin-walled subsurface reflection (1 when not thin-walled).
LayerState = collections.namedtuple("LayerState", ("E1s", "E5s", "E6s", "Es", "Ec", "Ef", "eg", "eh", "Eq"))


@block
def lobe_albedo(k, c, p, o, dmodel, ms, st):
    """E_k(wo), the directional albedo of lobe slot k in channel c, from the row's
    ``LayerState`` ``st``."""
    if k == DIFFUSE:
        return diffuse_albedo(dmodel, p[o + PARAM.BASE_COLOR + c], p[o + PARAM.RHO_MS + c], st.eg, st.eh)
    if k == SPECULAR:
        return st.Es
    if k == METAL:
        return metal_albedo(p, o, c, st.E1s, st.E5s, st.E6s, ms)
    if k == TRANSMISSION:
        return p[o + PARAM.TRANS_TINT + c]
    if k == SUBSURFACE:
        return p[o + PARAM.SSS_COLOR + c] * st.Eq
    if k == SUBSURFACE_T:
        return p[o + PARAM.SSS_COLOR + c]
    if k == COAT:
        return st.Ec
    return st.Ef


@block
def _norm_or_max(mx, a, b, c):
    """|(a, b, c)| (RGB length), or its largest component's magnitude when ``mx``."""
    return max(max(abs(a), abs(b)), abs(c)) if mx else math.sqrt(a * a + b * b + c * c)


@block
def lobe_score(k, sel, p, o, ms, L, st):
    """The selection score s_k = |w_k E_k| of lobe slot k (L = its ``layer_factor``; st: the
    row's ``LayerState``): the RGB
    length (SEL_LENGTH), the largest component (SEL_MAX) or 1 (SEL_UNIFORM).

    With w_k = L_k K_k most reduce to constants of the material (``_pack_weights``):
    s_k = |L_k| E_k |K_k| for the lobes whose albedo is a scalar (specular, coat, fuzz; the
    thin-walled subsurface's QON factor), |L_k| |K_k e_k| for a constant colour e_k
    (transmission, subsurface), and for the diffuse lobe, whose albedo is rho e_g +
    rho_ms e_h (Eq. 20; e_h = 0 for QON and Lambert), |L_0| sqrt(|K rho|^2 e_g^2 +
    2 (K rho).(K rho_ms) e_g e_h + |K rho_ms|^2 e_h^2) by length; only the metal lobe (and the
    diffuse one by max) is summed over channels.  Both rules are computed and one selected:
    a loop over rows calling it for one k has no branch."""
    mx = sel == SEL_MAX
    q = o + PARAM.K + 3 * k
    if k == DIFFUSE:
        d0 = p[q] * diffuse_albedo(D_EON, p[o + PARAM.BASE_COLOR], p[o + PARAM.RHO_MS], st.eg, st.eh)
        d1 = p[q + 1] * diffuse_albedo(D_EON, p[o + PARAM.BASE_COLOR + 1], p[o + PARAM.RHO_MS + 1], st.eg, st.eh)
        d2 = p[q + 2] * diffuse_albedo(D_EON, p[o + PARAM.BASE_COLOR + 2], p[o + PARAM.RHO_MS + 2], st.eg, st.eh)
        q2 = (
            p[o + PARAM.DQ] * st.eg * st.eg
            + 2.0 * p[o + PARAM.DQ + 1] * st.eg * st.eh
            + p[o + PARAM.DQ + 2] * st.eh * st.eh
        )
        s = _norm_or_max(True, d0, d1, d2) if mx else math.sqrt(max(q2, 0.0))
    elif k == METAL:
        m0 = p[q] * metal_albedo(p, o, opaque(0), st.E1s, st.E5s, st.E6s, ms)
        m1 = p[q + 1] * metal_albedo(p, o, opaque(1), st.E1s, st.E5s, st.E6s, ms)
        m2 = p[q + 2] * metal_albedo(p, o, opaque(2), st.E1s, st.E5s, st.E6s, ms)
        s = _norm_or_max(True, m0, m1, m2) if mx else _norm_or_max(False, m0, m1, m2)
    else:
        cl, cm = p[o + PARAM.SC + 2 * k], p[o + PARAM.SC + 2 * k + 1]
        c = cm if mx else cl
        if k == SPECULAR:
            s = st.Es * c
        elif k == COAT:
            s = st.Ec * c
        elif k == FUZZ:
            s = st.Ef * c
        elif k == SUBSURFACE:
            s = st.Eq * c
        else:  # TRANSMISSION, SUBSURFACE_T: constant colours
            s = c
    return 1.0 if sel == SEL_UNIFORM else abs(L) * s


@block
def diffuse_gh(dmodel, p, o, iz, oz, s):
    """(g, h) of the diffuse lobe's BSDF f = rho g + rho_ms h, channel-free: EON Eq. 16-19,
    QON Eq. 1 (the material's A, B: PARAM.QON_AB) or Lambert (h = 0 for both)."""
    if dmodel == D_EON:
        g, h, _ = eon_terms(iz, oz, s, p[o + PARAM.R_DIFF], False)
        return g, h
    if dmodel == D_QON:
        return qon_terms(iz, oz, s, p[o + PARAM.QON_AB], p[o + PARAM.QON_AB + 1]), 0.0
    return INV_PI, 0.0


# The lobes' own BSDFs, one function per lobe slot with one signature (the arguments of
# ``lobe_f``); ``lobe_f`` picks one by the lobe id.


@block
def f_diffuse(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    up = (iz > 0.0) & (oz > 0.0)
    s = ix * ox + iy * oy + iz * oz - iz * oz
    g, h = diffuse_gh(dmodel, p, o, iz, oz, s)
    g = g if up else 0.0
    h = h if up else 0.0
    return (
        p[o + PARAM.BASE_COLOR] * g + p[o + PARAM.RHO_MS] * h,
        p[o + PARAM.BASE_COLOR + 1] * g + p[o + PARAM.RHO_MS + 1] * h,
        p[o + PARAM.BASE_COLOR + 2] * g + p[o + PARAM.RHO_MS + 2] * h,
    )


@block
def f_specular(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    x = p[o + PARAM.X_S]
    v = m * fresnel.dielectric(c, p[o + PARAM.ETA_S]) * mf.multiscatter(x * x, E1s, ms)
    return v, v, v


@block
def f_metal(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    F0r, F0g, F0b = p[o + PARAM.METAL_F0], p[o + PARAM.METAL_F0 + 1], p[o + PARAM.METAL_F0 + 2]
    return (
        m * fresnel.f82(c, F0r, p[o + PARAM.METAL_A]) * mf.multiscatter(F0r, E1s, ms),
        m * fresnel.f82(c, F0g, p[o + PARAM.METAL_A + 1]) * mf.multiscatter(F0g, E1s, ms),
        m * fresnel.f82(c, F0b, p[o + PARAM.METAL_A + 2]) * mf.multiscatter(F0b, E1s, ms),
    )


@block
def f_transmission(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    """The GGX lobe mirrored below the surface, normalised by E1."""
    mt, _ = mf.reflection(ix, iy, -iz, ox, oy, oz, p[o + PARAM.ALPHA_S])
    mt = mt / E1s
    return mt * p[o + PARAM.TRANS_TINT], mt * p[o + PARAM.TRANS_TINT + 1], mt * p[o + PARAM.TRANS_TINT + 2]


@block
def f_subsurface(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    """QON when thin-walled (its reflection half), else Lambert."""
    up = (iz > 0.0) & (oz > 0.0)
    s = ix * ox + iy * oy + iz * oz - iz * oz
    q = qon_terms(iz, oz, s, p[o + PARAM.QON_AB], p[o + PARAM.QON_AB + 1])
    thin = p[o + PARAM.THIN] > 0.0
    g = q if thin else INV_PI
    g = g if up else 0.0
    return p[o + PARAM.SSS_COLOR] * g, p[o + PARAM.SSS_COLOR + 1] * g, p[o + PARAM.SSS_COLOR + 2] * g


@block
def f_subsurface_t(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    g = INV_PI if (iz < 0.0) & (oz > 0.0) else 0.0
    return p[o + PARAM.SSS_COLOR] * g, p[o + PARAM.SSS_COLOR + 1] * g, p[o + PARAM.SSS_COLOR + 2] * g


@block
def f_coat(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    mc, cc = mf.reflection(ix, iy, iz, ox, oy, oz, p[o + PARAM.ALPHA_C])
    x = p[o + PARAM.X_C]
    v = mc * fresnel.dielectric(cc, p[o + PARAM.ETA_C]) * mf.multiscatter(x * x, E1c, ms)
    return v, v, v


@block
def f_fuzz(p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef):
    up = (iz > 0.0) & (oz > 0.0)
    Xx, Xy = ltc_frame(ox, oy)
    lx, ly = to_frame(Xx, Xy, ix, iy)
    v = Ef * sheen_density(lx, ly, iz, oz, p[o + PARAM.FUZZ_R]) / iz
    v = v if up else 0.0
    return v, v, v


#: ``lobe_f``'s function of each lobe slot, in slot order
LOBE_F = (f_diffuse, f_specular, f_metal, f_transmission, f_subsurface, f_subsurface_t, f_coat, f_fuzz)


#: ``lobe_f(k, p, o, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c, E1s, E1c, Ef)``, compiled code
#: only, k a compile-time constant: the lobe's own BSDF (f0, f1, f2), weight not applied; 0
#: outside the lobe's hemisphere.  (m, c): ``microfacet.kernels.reflection`` at the base
#: specular's alpha, shared by the specular and metal lobes (computed once per row by the
#: caller); E1s, E1c: the GGX albedo E1 of the base specular and the coat (multiple-scattering
#: factors, the transmission's normalisation); Ef: the fuzz albedo.  Branches on the
#: directions are selects, so that a loop over rows calling it for one lobe vectorises.
lobe_f = by_constant(
    "lobe_f",
    ("k", "p", "o", "ix", "iy", "iz", "ox", "oy", "oz", "dmodel", "ms", "m", "c", "E1s", "E1c", "Ef"),
    LOBE_F,
    __name__,
)


@block
def diffuse_uses_eon_sampler(k, dmodel):
    return k == DIFFUSE and dmodel == D_EON


@block
def lobe_pdf(k, p, o, ix, iy, iz, ox, oy, oz, dmodel, vndf, pdf_s):
    """Solid-angle pdf of ``lobe_sample`` producing wi given wo (wo above the horizon);
    ``pdf_s``: the GGX reflection pdf at the base specular's alpha (specular and metal)."""
    if k == DIFFUSE or k == SUBSURFACE:
        if diffuse_uses_eon_sampler(k, dmodel):
            Xx, Xy = ltc_frame(ox, oy)
            lx, ly = to_frame(Xx, Xy, ix, iy)
            q = eon_pdf(lx, ly, iz, min(oz, 1.0), p[o + PARAM.R_DIFF], p[o + PARAM.R_TENTH])
        else:
            q = cosine_pdf(iz)
        return q if iz > 0.0 else 0.0  # a select: no branch on the direction
    if k == SUBSURFACE_T:
        return cosine_pdf(-iz)
    if k == FUZZ:
        Xx, Xy = ltc_frame(ox, oy)
        lx, ly = to_frame(Xx, Xy, ix, iy)
        return sheen_density(lx, ly, iz, oz, p[o + PARAM.FUZZ_R])
    if k == TRANSMISSION:
        return mf.reflection_pdf(ix, iy, -iz, ox, oy, oz, p[o + PARAM.ALPHA_S], vndf)
    if k == COAT:
        return mf.reflection_pdf(ix, iy, iz, ox, oy, oz, p[o + PARAM.ALPHA_C], vndf)
    return pdf_s


@block
def uses_base_ggx(active):
    return (active & ((1 << SPECULAR) | (1 << METAL))) != 0


#: The samplers of the lobes (``sampler_of``): the EON sampler (EON paper Listing 4; the EON
#: diffuse lobe), cosine sampling (the other diffuse models, subsurface, translucency),
#: GGX (visible normals or the NDF: specular, metal, transmission, coat) and the fuzz
#: lobe's LTC.
S_EON, S_COSINE, S_GGX, S_SHEEN = range(4)
N_SAMPLERS = 4

#: The floor of |wi.z| of the hemisphere samplers: the smallest normal float64.
Z_MIN = float(np.finfo(np.float64).tiny)


@block
def sampler_of(k, dmodel):
    """The sampler of lobe slot k."""
    if k == DIFFUSE:
        return S_EON if dmodel == D_EON else S_COSINE
    if k == SUBSURFACE or k == SUBSURFACE_T:
        return S_COSINE
    if k == FUZZ:
        return S_SHEEN
    return S_GGX


@block
def lobe_sample(sampler, k, p, o, ox, oy, oz, u1, u2, vndf):
    """(x, y, z, ok): a direction from lobe slot k (a float: the row's chosen lobe) drawn by its
    ``sampler`` (a constant of the caller's loop; the lobe only selects the GGX width and the
    side of the surface); ok is False when the sampler failed (a GGX NDF normal facing away
    from wo).

    The hemisphere samplers never return z = 0: as in ``sampling`` (``sample``), |z| is
    floored at ``Z_MIN``, which only rounding reaches (the uniform lobe's z = u1 at u1 = 0,
    a CLTC direction on the clipped boundary), so that the sample lies in its lobe and its
    pdf is the lobe's pdf there."""
    if sampler == S_GGX:
        a_s, a_c = p[o + PARAM.ALPHA_S], p[o + PARAM.ALPHA_C]
        x, y, z, ok = mf.sample_reflection(ox, oy, oz, a_c if k == COAT else a_s, u1, u2, vndf)
        return x, y, (-z if k == TRANSMISSION else z), ok
    mu = min(max(oz, 0.0), 1.0)
    Xx, Xy = ltc_frame(ox, oy)
    if sampler == S_EON:
        x, y, z, _ = eon_sample(Xx, Xy, mu, p[o + PARAM.R_DIFF], p[o + PARAM.R_TENTH], u1, u2)
        return x, y, max(z, Z_MIN), True
    if sampler == S_SHEEN:
        lx, ly, z = sheen_sample(mu, p[o + PARAM.FUZZ_R], u1, u2)
    else:
        lx, ly, z, _ = cosine_sample_local(u1, u2)
    x, y = from_frame(Xx, Xy, lx, ly)
    z = max(z, Z_MIN)
    return x, y, (-z if k == SUBSURFACE_T else z), True
