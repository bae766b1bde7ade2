"""The compiled path of ``OpenPBRSurface``: its lobes as scalar functions, and one batch
driver per verb.

Lobes are plain values with the verbs of pbrt-v4's ``BxDF`` -- ``lobe_f`` (the lobe's own
BSDF, weight not applied), ``lobe_sample`` and ``lobe_pdf`` -- selected by a lobe id, and
``weights_albedos`` (every lobe's mixture weight w_k(wo) and directional albedo E_k(wo)).  A
surface row is a flat vector of prepared parameters (layout ``P_*``, built once per
material by ``openpbr_surface.pack_parameters``); the wo-dependent layer factors (the
albedos of the specular, coat and fuzz layers, which scale what lies beneath) are looked up
once per row (``row_state``) and shared by every lobe.  Each weight is such a layer factor
times a colour of the material, w_k[c] = L_k(wo) K_k[c] (``layer_factors``,
``_pack_weights``), so that the lobe selection scores |w_k E_k| are constants of the material
times functions of mu_o (``all_scores``).  No input is checked here: the public class checks
its inputs once, at construction and on each call's directions.

The per-row code does not vectorise (it switches between lobes); its time is the latency of
chains of square roots and divisions, so the kernels it calls are written with as few of
them on a row's path as the formulas allow (``microfacet.kernels``, ``sampling.ltc``).

Lobe ids (slots): DIFFUSE, SPECULAR, METAL, TRANSMISSION, SUBSURFACE (the thin-walled
reflection part when thin-walled), SUBSURFACE_T (thin-walled translucency), COAT, FUZZ.
"""
import functools
import math
import types

import numba
import numpy as np
from numba import prange

from .._jit import FASTMATH, INV_PI, kernel
from .._launch import _F, _U, compiled, launch, rows
from ..microfacet import fresnel
from ..microfacet import kernels as mf
from ..microfacet.sheen import sheen_albedo_at, sheen_albedo_fit, sheen_density, sheen_sample
from ..microfacet.tables import MU_AXIS, R_AXIS, X_AXIS, catmull_rom_at, node_at
from ..models.eon import eon_albedo_at, eon_albedo_fit, eon_terms, rho_ms
from ..models.fon import E_F_avg
from ..models.qon import qon_AB, qon_albedo, qon_terms
from ..sampling.ltc import from_frame, ltc_frame, to_frame
from ..sampling.mis import eon_pdf, eon_sample, pow_tenth
from ..sampling.simple import U_MAX, cosine_pdf, cosine_sample_local

DIFFUSE, SPECULAR, METAL, TRANSMISSION, SUBSURFACE, SUBSURFACE_T, COAT, FUZZ = range(8)
N_LOBES = 8
LOBE_NAMES = ("diffuse", "specular", "metal", "transmission", "subsurface", "subsurface_transmission",
              "coat", "fuzz")
#: diffuse lobe models
D_EON, D_QON, D_LAMBERT = 0, 1, 2
#: selection rules
SEL_LENGTH, SEL_MAX, SEL_UNIFORM = 0, 1, 2

# parameter layout of one surface row (float64)
P_BASE_COLOR = 0          # 3: rho of the diffuse lobe
P_R_DIFF = 3              # base_diffuse_roughness (EON r; QON sigma)
P_BASE_WEIGHT = 4
P_METAL = 5               # base_metalness
P_SPEC_COLOR = 6          # 3
P_SPEC_WEIGHT = 9
P_ALPHA_S = 10            # GGX alpha of the base specular and metal (coat-affected)
P_R_S = 11                # its roughness (table coordinate)
P_X_S = 12                # |sqrt(F0)| of the modulated index (table coordinate)
P_ETA_S = 13              # modulated index eta' >= 1
P_METAL_F0 = 14           # 3: base_weight * base_color
P_METAL_A = 17            # 3: F82-tint coefficient a
P_TRANS_W = 20
P_TRANS_TINT = 21         # 3
P_SSS_W = 24
P_SSS_COLOR = 25          # 3
P_SSS_ANISO = 28
P_COAT_W = 29
P_ALPHA_C = 30
P_R_C = 31
P_X_C = 32
P_ETA_C = 33
P_BASE_MUL = 34           # 3: coat attenuation x darkening of everything under the coat
P_FUZZ_W = 37
P_FUZZ_COLOR = 38         # 3
P_FUZZ_R = 41
P_THIN = 42               # geometry_thin_walled (0/1)
# table axes fixed per material (``microfacet.tables.axis_weights``): for the base specular
# (P_TAB_S) and the coat (P_TAB_C), the conductor table's roughness node and 4 weights, the
# dielectric table's roughness node and 4 weights, its x node and 4 weights
P_TAB_S = 43              # 15
P_TAB_C = 58              # 15
# the dielectric table collapsed on those two axes: E_diel/E1 at every (padded) mu node of the
# table, for the base specular and the coat; per row only a 4-point cubic in mu remains
N_CURVE = 35              # mu nodes of the dielectric table + 2 ghost nodes
P_CURVE_S = 73
P_CURVE_C = P_CURVE_S + N_CURVE
# the conductor table collapsed on its roughness axis: E1, E5, E6 of the base specular's
# roughness and E1 of the coat's at every (padded) mu node; per row only a 4-point cubic in
# mu remains (``_conductor_curve``)
N_CCURVE = 67             # mu nodes of the conductor table + 2 ghost nodes
P_E1S = P_CURVE_C + N_CURVE
P_E5S = P_E1S + N_CCURVE
P_E6S = P_E5S + N_CCURVE
P_E1C = P_E6S + N_CCURVE
# values of one material that the per-row formulas would otherwise recompute
P_R_TENTH = P_E1C + N_CCURVE   # base_diffuse_roughness^0.1 (the EON sampler's P_u)
P_RHO_MS = P_R_TENTH + 1       # 3: rho_ms(base_color, <E_F>) of the EON lobe (Eq. 18)
P_SHEEN_FIT = P_RHO_MS + 3     # 3: (s, m, o) of the fuzz albedo fit at fuzz_roughness
# every lobe's weight is a layer factor of mu_o times a constant of the material,
# w_k[c](wo) = L_k(wo) K_k[c] (``layer_factors``); the selection scores |w_k E_k| then
# reduce to constants of the material times functions of mu_o (``all_scores``)
P_K = P_SHEEN_FIT + 3          # 8 x 3: K_k[c]
P_SC = P_K + 3 * N_LOBES       # 8 x 2: |K_k e_k| and max_c |K_k[c] e_k[c]| for the lobes whose albedo is
                               # a constant colour e_k or a scalar times 1 (e_k = 1)
P_DQ = P_SC + 2 * N_LOBES      # 3: |K rho|^2, (K rho).(K rho_ms), |K rho_ms|^2 of the diffuse lobe
P_EON_FIT = P_DQ + 3           # 3: (A_F, B_F, s_h) of the EON albedo at base_diffuse_roughness
P_QON_AB = P_EON_FIT + 3       # 2: QON's (A, B) at base_diffuse_roughness (QON diffuse, thin-walled subsurface)
N_PARAMS = P_QON_AB + 2


# --------------------------------------------------------------------------- packing
# The material's inputs, in this order (float64; colours 3 wide), are packed into the
# parameter layout above by ``pack_drive``, once per material.
RAW = (("base_color", 3), ("base_diffuse_roughness", 1), ("base_weight", 1), ("base_metalness", 1),
       ("specular_color", 3), ("specular_weight", 1), ("specular_roughness", 1), ("specular_ior", 1),
       ("transmission_weight", 1), ("transmission_color", 3), ("transmission_depth", 1),
       ("subsurface_weight", 1), ("subsurface_color", 3), ("subsurface_scatter_anisotropy", 1),
       ("coat_weight", 1), ("coat_color", 3), ("coat_roughness", 1), ("coat_ior", 1), ("coat_darkening", 1),
       ("fuzz_weight", 1), ("fuzz_color", 3), ("fuzz_roughness", 1), ("geometry_thin_walled", 1))
N_RAW = sum(w for _, w in RAW)
#: warning bits of ``pack_drive``
W_SPEC_TIR, W_COAT_TIR, W_F82_NEGATIVE = 1, 2, 4


@kernel
def _axes(out, q, v, n, kind):
    """Node index and Catmull-Rom weights of v on a table axis, into out[q:q + 5]."""
    i, t = node_at(v, n, kind)
    w0, w1, w2, w3 = catmull_rom_at(t)
    out[q] = i
    out[q + 1] = w0
    out[q + 2] = w1
    out[q + 3] = w2
    out[q + 4] = w3


@kernel
def _table_axes(out, q, r, x, nCr, nRr, nRx):
    _axes(out, q, r, nCr, R_AXIS)
    _axes(out, q + 5, r, nRr, R_AXIS)
    _axes(out, q + 10, x, nRx, X_AXIS)


@kernel
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


@kernel
def _conductor_curve(out, q, t, C, c):
    """out[q + m] = basis albedo c of the conductor table at the roughness whose node and
    weights are out[t:t + 5], for every padded mu node m."""
    ir = int(out[t])
    for m in range(N_CCURVE):
        out[q + m] = (out[t + 1] * C[ir, m, c] + out[t + 2] * C[ir + 1, m, c] + out[t + 3] * C[ir + 2, m, c]
                      + out[t + 4] * C[ir + 3, m, c])


@kernel
def _pack_weights(out, o):
    """The material part K_k[c] of every lobe's weight (P_K), following the reference graph
    (open_pbr_surface.mtlx): the base attenuated by the coat (P_BASE_MUL); metal /
    dielectric by base_metalness; under the dielectric specular layer the substrate mixes
    transmission, subsurface and diffuse; the subsurface lobe is Lambert, or when thin-walled
    the reflection half of the thin-walled mix (QON, colour^2 (1 - g)/2) and SUBSURFACE_T its
    translucent half.  Then the score constants (P_SC, P_DQ) of ``all_scores``."""
    M, T, S, g = out[o + P_METAL], out[o + P_TRANS_W], out[o + P_SSS_W], out[o + P_SSS_ANISO]
    thin = out[o + P_THIN] > 0.0
    for c in range(3):
        base = out[o + P_BASE_MUL + c]
        diel = base * (1.0 - M)
        opaque = diel * (1.0 - T)
        color = out[o + P_SSS_COLOR + c]
        K = (opaque * (1.0 - S) * out[o + P_BASE_WEIGHT],              # DIFFUSE
             diel * out[o + P_SPEC_COLOR + c],                          # SPECULAR
             base * M * out[o + P_SPEC_WEIGHT],                         # METAL
             diel * T,                                                  # TRANSMISSION
             opaque * S * 0.5 * color * (1.0 - g) if thin else opaque * S,   # SUBSURFACE
             opaque * S * 0.5 * color * (1.0 + g),                      # SUBSURFACE_T
             out[o + P_COAT_W],                                         # COAT
             out[o + P_FUZZ_W] * out[o + P_FUZZ_COLOR + c])             # FUZZ
        for k in range(N_LOBES):
            out[o + P_K + 3 * k + c] = K[k]
    for k in range(N_LOBES):
        n2 = 0.0
        mx = 0.0
        for c in range(3):
            e = 1.0   # SPECULAR, COAT, FUZZ (scalar albedos), and DIFFUSE, METAL (unused)
            if k == TRANSMISSION:
                e = out[o + P_TRANS_TINT + c]
            elif k == SUBSURFACE or k == SUBSURFACE_T:
                e = out[o + P_SSS_COLOR + c]
            v = out[o + P_K + 3 * k + c] * e
            n2 += v * v
            mx = max(mx, abs(v))
        out[o + P_SC + 2 * k] = math.sqrt(n2)
        out[o + P_SC + 2 * k + 1] = mx
    a = b = d = 0.0
    for c in range(3):
        x = out[o + P_K + c] * out[o + P_BASE_COLOR + c]
        y = out[o + P_K + c] * out[o + P_RHO_MS + c]
        a += x * x
        b += x * y
        d += y * y
    out[o + P_DQ], out[o + P_DQ + 1], out[o + P_DQ + 2] = a, b, d


def _pack_drive(raw, out, CT, RT):
    """Pack rows of RAW inputs into parameter rows (the reference graph's derived values);
    returns (mask of the lobes active in some row, warning bits)."""
    m = raw.shape[0] // N_RAW
    mask = 0
    warn = 0
    nCr, nRr, nRx = CT.shape[0] - 2, RT.shape[0] - 2, RT.shape[1] - 2
    for i in range(m):
        a = i * N_RAW
        o = i * N_PARAMS
        bw, M, sw = raw[a + 4], raw[a + 5], raw[a + 9]
        r_s, ior = raw[a + 10], raw[a + 11]
        T, S, g = raw[a + 12], raw[a + 17], raw[a + 21]
        C, r_c, c_ior, c_dark = raw[a + 22], raw[a + 26], raw[a + 27], raw[a + 28]
        F, thin = raw[a + 29], raw[a + 34]
        # the coat's effect on the base specular [effective_specular_roughness, eta_s]
        r_eff = (1.0 - C) * r_s + C * min(1.0, 2.0 * r_c ** 4 + r_s ** 4) ** 0.25
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
            bc = raw[a + c]
            sc = raw[a + 6 + c]
            out[o + P_BASE_COLOR + c] = bc
            out[o + P_SPEC_COLOR + c] = sc
            F0 = bw * bc
            out[o + P_METAL_F0 + c] = F0
            am = fresnel.f82_a(F0, sc)
            out[o + P_METAL_A + c] = am
            if M > 0.0 and sw > 0.0:
                for k in range(257):
                    if fresnel.f82(k / 256.0, F0, am) < 0.0:
                        warn |= W_F82_NEGATIVE
            out[o + P_TRANS_TINT + c] = 1.0 if raw[a + 16] > 0.0 else raw[a + 13 + c]
            ssc = raw[a + 18 + c]
            out[o + P_SSS_COLOR + c] = ssc
            # base darkening and coat attenuation [Kcoat, Ebase, base_darkening, coat_attenuation]
            E_base = (1.0 - M) * ((1.0 - S) * bc + S * ssc) + M * bc * sw
            dark = (1.0 - K) / (1.0 - E_base * K)
            out[o + P_BASE_MUL + c] = (1.0 + C * c_dark * (dark - 1.0)) * (1.0 + C * (raw[a + 23 + c] - 1.0))
            out[o + P_FUZZ_COLOR + c] = raw[a + 30 + c]
        out[o + P_R_DIFF] = raw[a + 3]
        out[o + P_R_TENTH] = pow_tenth(raw[a + 3])
        avg = E_F_avg(raw[a + 3])
        for c in range(3):
            out[o + P_RHO_MS + c] = rho_ms(raw[a + c], avg)
        out[o + P_SHEEN_FIT], out[o + P_SHEEN_FIT + 1], out[o + P_SHEEN_FIT + 2] = sheen_albedo_fit(raw[a + 33])
        out[o + P_EON_FIT], out[o + P_EON_FIT + 1], out[o + P_EON_FIT + 2] = eon_albedo_fit(raw[a + 3])
        out[o + P_QON_AB], out[o + P_QON_AB + 1] = qon_AB(raw[a + 3], 0.33)
        out[o + P_BASE_WEIGHT] = bw
        out[o + P_METAL] = M
        out[o + P_SPEC_WEIGHT] = sw
        out[o + P_ALPHA_S] = mf.alpha_of(r_eff)
        out[o + P_R_S] = r_eff
        out[o + P_X_S] = x
        out[o + P_ETA_S] = fresnel.eta_of_x(x)
        out[o + P_TRANS_W] = T
        out[o + P_SSS_W] = S
        out[o + P_SSS_ANISO] = g
        out[o + P_COAT_W] = C
        out[o + P_ALPHA_C] = mf.alpha_of(r_c)
        out[o + P_R_C] = r_c
        out[o + P_X_C] = xc
        out[o + P_ETA_C] = fresnel.eta_of_x(xc)
        out[o + P_FUZZ_W] = F
        out[o + P_FUZZ_R] = raw[a + 33]
        out[o + P_THIN] = thin
        _table_axes(out, o + P_TAB_S, r_eff, x, nCr, nRr, nRx)
        _table_axes(out, o + P_TAB_C, r_c, xc, nCr, nRr, nRx)
        _curve(out, o + P_CURVE_S, o + P_TAB_S, RT)
        _curve(out, o + P_CURVE_C, o + P_TAB_C, RT)
        _conductor_curve(out, o + P_E1S, o + P_TAB_S, CT, 0)
        _conductor_curve(out, o + P_E5S, o + P_TAB_S, CT, 1)
        _conductor_curve(out, o + P_E6S, o + P_TAB_S, CT, 2)
        _conductor_curve(out, o + P_E1C, o + P_TAB_C, CT, 0)
        _pack_weights(out, o)
        # lobes that can be non-zero
        diel = 1.0 - M
        sc_any = raw[a + 6] > 0.0 or raw[a + 7] > 0.0 or raw[a + 8] > 0.0
        on = ((diel * (1.0 - T) * (1.0 - S) * bw > 0.0, diel > 0.0 and x > 0.0 and sc_any, M > 0.0 and sw > 0.0,
               diel * T > 0.0, diel * (1.0 - T) * S > 0.0, thin > 0.0 and diel * (1.0 - T) * S > 0.0, C > 0.0, F > 0.0))
        for k in range(N_LOBES):
            if on[k]:
                mask |= 1 << k
    return mask, warn


pack_drive = numba.njit(cache=True, error_model="numpy")(_pack_drive)


@kernel
def cubic_at(p, b, w0, w1, w2, w3):
    return w0 * p[b] + w1 * p[b + 1] + w2 * p[b + 2] + w3 * p[b + 3]


@kernel
def layer_albedos(p, o, e1, e5, e6, q, mu, x, ms):
    """(E1, E5, E6, E) of a GGX layer from its curves collapsed per material: the conductor
    basis at p[o + e1], p[o + e5], p[o + e6] (P_E*), the dielectric ratio at p[o + q]
    (P_CURVE_*): the basis albedos and the dielectric lobe's albedo with the
    multiple-scattering factor (0 at x = 0: index-matched)."""
    im, tm = node_at(mu, N_CCURVE - 2, MU_AXIS)
    w0, w1, w2, w3 = catmull_rom_at(tm)
    E1 = min(max(cubic_at(p, o + e1 + im, w0, w1, w2, w3), 0.0), 1.0)
    E5 = max(cubic_at(p, o + e5 + im, w0, w1, w2, w3), 0.0)
    E6 = max(cubic_at(p, o + e6 + im, w0, w1, w2, w3), 0.0)
    E = 0.0
    if x > 0.0:
        im, tm = node_at(mu, N_CURVE - 2, MU_AXIS)
        w0, w1, w2, w3 = catmull_rom_at(tm)
        E = min(max(cubic_at(p, o + q + im, w0, w1, w2, w3), 0.0), 1.0) * E1
    return E1, E5, E6, E * mf.multiscatter(x * x, E1, ms)


@kernel
def diffuse_albedo_terms(dmodel, p, o, mu):
    """(e_g, e_h) of the diffuse lobe's albedo rho e_g + m(rho) e_h (channel-free): EON
    Eq. 20 (m = rho_ms), QON Eq. 8 or Lambert (m = 0), from the material's fits (P_EON_FIT,
    P_QON_AB)."""
    if dmodel == D_EON:
        return eon_albedo_at(mu, p[o + P_EON_FIT], p[o + P_EON_FIT + 1], p[o + P_EON_FIT + 2])
    if dmodel == D_QON:
        return qon_albedo(mu, p[o + P_QON_AB], p[o + P_QON_AB + 1]), 0.0
    return 1.0, 0.0


@kernel
def row_state(p, o, mu, dmodel, ms, albedos=True):
    """Per-row quantities shared by every lobe at mu_o: (E1_s, E5_s, E6_s, E_spec, E1_c,
    E_coat, E_fuzz, e_g, e_h, E_qon).

    E1/E5/E6: GGX basis albedos of the base specular roughness; E_spec, E_coat: albedos of
    the dielectric specular and coat lobes (with the multiple-scattering factor); E_fuzz:
    the sheen albedo; e_g, e_h: the diffuse albedo terms; E_qon: the QON albedo of
    the thin-walled subsurface reflection (0 unless ``albedos``).  Layers that are off are
    not looked up.
    """
    E1s, E5s, E6s, Es = layer_albedos(p, o, P_E1S, P_E5S, P_E6S, P_CURVE_S, mu, p[o + P_X_S], ms)
    E1c, Ec, Ef, Eq = 1.0, 0.0, 0.0, 0.0
    if p[o + P_COAT_W] > 0.0:
        E1c, _, _, Ec = layer_albedos(p, o, P_E1C, P_E1C, P_E1C, P_CURVE_C, mu, p[o + P_X_C], ms)
    if p[o + P_FUZZ_W] > 0.0:
        Ef = sheen_albedo_at(mu, p[o + P_SHEEN_FIT], p[o + P_SHEEN_FIT + 1], p[o + P_SHEEN_FIT + 2])
    eg, eh = 0.0, 0.0
    if albedos:   # the weights do not need the diffuse albedos (eval does not)
        eg, eh = diffuse_albedo_terms(dmodel, p, o, mu)
    if albedos and p[o + P_THIN] > 0.0 and p[o + P_SSS_W] > 0.0:
        Eq, _ = diffuse_albedo_terms(D_QON, p, o, mu)
    return E1s, E5s, E6s, Es, E1c, Ec, Ef, eg, eh, Eq


@kernel
def diffuse_albedo(dmodel, rho, rms, eg, eh):
    """One channel of the diffuse albedo from ``diffuse_albedo_terms``; rms = rho_ms(rho)."""
    if dmodel == D_EON:
        return rho * eg + rms * eh
    return rho * eg


@kernel
def metal_albedo(p, o, c, E1, E5, E6, ms):
    """F82-tint GGX albedo F0 (E1 - E5) + E5 - a E6 (times the multiple-scattering factor)."""
    F0 = p[o + P_METAL_F0 + c]
    return (F0 * (E1 - E5) + E5 - p[o + P_METAL_A + c] * E6) * mf.multiscatter(F0, E1, ms)


@kernel
def layer_factors(p, o, st):
    """(L_0, ..., L_7): the part of each lobe's weight that depends on wo, w_k[c] = L_k K_k[c].

    Each layer passes 1 - weight E_layer(mu_o) of what lies beneath (albedo scaling): fuzz
    over coat over the base, and the dielectric specular layer over transmission,
    subsurface and diffuse (``_pack_weights`` holds the material part)."""
    Es, Ec, Ef = st[3], st[5], st[6]
    Tf = 1.0 - p[o + P_FUZZ_W] * Ef
    Tb = Tf * (1.0 - p[o + P_COAT_W] * Ec)
    Tu = Tb * (1.0 - Es)
    return Tu, Tb, Tb, Tu, Tu, Tu, Tf, 1.0


@kernel
def lobe_albedos(c, p, o, st, dmodel, ms):
    """(E_0, ..., E_7): the directional albedo E_k(wo) of every lobe slot in channel c."""
    E1s, E5s, E6s, Es, E1c, Ec, Ef, eg, eh, Eq = st
    color = p[o + P_SSS_COLOR + c]
    return (diffuse_albedo(dmodel, p[o + P_BASE_COLOR + c], p[o + P_RHO_MS + c], eg, eh),
            Es,
            metal_albedo(p, o, c, E1s, E5s, E6s, ms),
            p[o + P_TRANS_TINT + c],
            color * Eq if p[o + P_THIN] > 0.0 else color,
            color,
            Ec,
            Ef)


@kernel
def weights_albedos(c, p, o, st, dmodel, ms):
    """((w_0, ..., w_7), (E_0, ..., E_7)): the mixture weight w_k(wo) = L_k K_k[c] and the
    albedo E_k(wo) of every lobe slot in channel c.  Slots that are not active get the values
    the formulas give (the drivers skip them)."""
    L = layer_factors(p, o, st)
    q = o + P_K + c
    w = (L[0] * p[q], L[1] * p[q + 3], L[2] * p[q + 6], L[3] * p[q + 9], L[4] * p[q + 12], L[5] * p[q + 15],
         L[6] * p[q + 18], L[7] * p[q + 21])
    return w, lobe_albedos(c, p, o, st, dmodel, ms)


@kernel
def diffuse_gh(dmodel, p, o, iz, oz, s):
    """(g, h) of the diffuse lobe's BSDF f = rho g + rho_ms h, channel-free: EON Eq. 16-19,
    QON Eq. 1 (the material's A, B: P_QON_AB) or Lambert (h = 0 for both)."""
    if dmodel == D_EON:
        g, h, _ = eon_terms(iz, oz, s, p[o + P_R_DIFF], False)
        return g, h
    if dmodel == D_QON:
        return qon_terms(iz, oz, s, p[o + P_QON_AB], p[o + P_QON_AB + 1]), 0.0
    return INV_PI, 0.0


@kernel
def lobe_f(k, p, o, st, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c):
    """The lobe's own BSDF (f0, f1, f2), weight not applied; 0 outside the lobe's hemisphere.

    (m, c): ``microfacet.kernels.reflection`` at the base specular's alpha, shared by the
    specular and metal lobes (computed once per row by the caller, ``base_ggx``)."""
    E1s, E5s, E6s, Es, E1c, Ec, Ef, eg, eh, Eq = st
    up = iz > 0.0 and oz > 0.0
    if k == DIFFUSE or k == SUBSURFACE:
        if not up:
            return 0.0, 0.0, 0.0
        s = ix * ox + iy * oy + iz * oz - iz * oz
        if k == SUBSURFACE:
            g, _ = diffuse_gh(D_QON if p[o + P_THIN] > 0.0 else D_LAMBERT, p, o, iz, oz, s)
            return p[o + P_SSS_COLOR] * g, p[o + P_SSS_COLOR + 1] * g, p[o + P_SSS_COLOR + 2] * g
        g, h = diffuse_gh(dmodel, p, o, iz, oz, s)
        return (p[o + P_BASE_COLOR] * g + p[o + P_RHO_MS] * h, p[o + P_BASE_COLOR + 1] * g + p[o + P_RHO_MS + 1] * h,
                p[o + P_BASE_COLOR + 2] * g + p[o + P_RHO_MS + 2] * h)
    if k == SUBSURFACE_T:
        if iz < 0.0 and oz > 0.0:
            return p[o + P_SSS_COLOR] * INV_PI, p[o + P_SSS_COLOR + 1] * INV_PI, p[o + P_SSS_COLOR + 2] * INV_PI
        return 0.0, 0.0, 0.0
    if k == FUZZ:
        if not up:
            return 0.0, 0.0, 0.0
        Xx, Xy = ltc_frame(ox, oy)
        lx, ly = to_frame(Xx, Xy, ix, iy)
        v = Ef * sheen_density(lx, ly, iz, oz, p[o + P_FUZZ_R]) / iz
        return v, v, v
    if k == TRANSMISSION:   # the GGX lobe mirrored below the surface, normalised by E1
        mt, _ = mf.reflection(ix, iy, -iz, ox, oy, oz, p[o + P_ALPHA_S])
        mt = mt / E1s
        return mt * p[o + P_TRANS_TINT], mt * p[o + P_TRANS_TINT + 1], mt * p[o + P_TRANS_TINT + 2]
    if k == COAT:
        mc, cc = mf.reflection(ix, iy, iz, ox, oy, oz, p[o + P_ALPHA_C])
        x = p[o + P_X_C]
        v = mc * fresnel.dielectric(cc, p[o + P_ETA_C]) * mf.multiscatter(x * x, E1c, ms)
        return v, v, v
    if k == SPECULAR:
        x = p[o + P_X_S]
        v = m * fresnel.dielectric(c, p[o + P_ETA_S]) * mf.multiscatter(x * x, E1s, ms)
        return v, v, v
    # METAL
    F0r, F0g, F0b = p[o + P_METAL_F0], p[o + P_METAL_F0 + 1], p[o + P_METAL_F0 + 2]
    return (m * fresnel.f82(c, F0r, p[o + P_METAL_A]) * mf.multiscatter(F0r, E1s, ms),
            m * fresnel.f82(c, F0g, p[o + P_METAL_A + 1]) * mf.multiscatter(F0g, E1s, ms),
            m * fresnel.f82(c, F0b, p[o + P_METAL_A + 2]) * mf.multiscatter(F0b, E1s, ms))


@kernel
def diffuse_uses_eon_sampler(k, dmodel):
    return k == DIFFUSE and dmodel == D_EON


@kernel
def lobe_pdf(k, p, o, ix, iy, iz, ox, oy, oz, dmodel, vndf, pdf_s):
    """Solid-angle pdf of ``lobe_sample`` producing wi given wo (wo above the horizon);
    ``pdf_s``: the GGX reflection pdf at the base specular's alpha (specular and metal)."""
    if k == DIFFUSE or k == SUBSURFACE:
        if diffuse_uses_eon_sampler(k, dmodel):
            Xx, Xy = ltc_frame(ox, oy)
            lx, ly = to_frame(Xx, Xy, ix, iy)
            q = eon_pdf(lx, ly, iz, min(oz, 1.0), p[o + P_R_DIFF], p[o + P_R_TENTH])
        else:
            q = cosine_pdf(iz)
        return q if iz > 0.0 else 0.0   # a select: no branch on the direction
    if k == SUBSURFACE_T:
        return cosine_pdf(-iz)
    if k == FUZZ:
        Xx, Xy = ltc_frame(ox, oy)
        lx, ly = to_frame(Xx, Xy, ix, iy)
        return sheen_density(lx, ly, iz, oz, p[o + P_FUZZ_R])
    if k == TRANSMISSION:
        return mf.reflection_pdf(ix, iy, -iz, ox, oy, oz, p[o + P_ALPHA_S], vndf)
    if k == COAT:
        return mf.reflection_pdf(ix, iy, iz, ox, oy, oz, p[o + P_ALPHA_C], vndf)
    return pdf_s


@kernel
def uses_base_ggx(active):
    return (active & ((1 << SPECULAR) | (1 << METAL))) != 0


#: the lobes sampled through GGX visible normals (or the NDF): their sampler has no
#: cheaper pdf than ``lobe_pdf``, which the mixture evaluates for every lobe anyway
GGX_LOBES = (1 << SPECULAR) | (1 << METAL) | (1 << TRANSMISSION) | (1 << COAT)


@kernel
def lobe_sample(k, p, o, ox, oy, oz, u1, u2, dmodel, vndf):
    """(x, y, z, own, ok): a direction from lobe k and, outside ``GGX_LOBES``, the density
    its sampler computed with it (that of ``lobe_pdf``; 0 for the GGX lobes)."""
    mu = min(max(oz, 0.0), 1.0)
    if k == DIFFUSE or k == SUBSURFACE or k == SUBSURFACE_T or k == FUZZ:
        Xx, Xy = ltc_frame(ox, oy)
        if diffuse_uses_eon_sampler(k, dmodel):
            x, y, z, q = eon_sample(Xx, Xy, mu, p[o + P_R_DIFF], p[o + P_R_TENTH], u1, u2)
            return x, y, z, q, True
        if k == FUZZ:
            lx, ly, z = sheen_sample(mu, p[o + P_FUZZ_R], u1, u2)
            x, y = from_frame(Xx, Xy, lx, ly)
            return x, y, z, sheen_density(lx, ly, z, mu, p[o + P_FUZZ_R]), True
        lx, ly, z, q = cosine_sample_local(u1, u2)
        x, y = from_frame(Xx, Xy, lx, ly)
        if k == SUBSURFACE_T:
            z = -z
        return x, y, z, q, True
    alpha = p[o + P_ALPHA_C] if k == COAT else p[o + P_ALPHA_S]
    x, y, z, ok = mf.sample_reflection(ox, oy, oz, alpha, u1, u2, vndf)
    if k == TRANSMISSION:
        z = -z
    return x, y, z, 0.0, ok


@kernel
def weights_albedos_rgb(p, o, st, dmodel, ms):
    """``weights_albedos`` in the three channels: (w_r, w_g, w_b, E_r, E_g, E_b), each a
    tuple over the 8 lobe slots."""
    w0, e0 = weights_albedos(0, p, o, st, dmodel, ms)
    w1, e1 = weights_albedos(1, p, o, st, dmodel, ms)
    w2, e2 = weights_albedos(2, p, o, st, dmodel, ms)
    return w0, w1, w2, e0, e1, e2


@kernel
def _norm_or_max(mx, a, b, c):
    """|(a, b, c)| (RGB length), or its largest component's magnitude when ``mx``."""
    return max(max(abs(a), abs(b)), abs(c)) if mx else math.sqrt(a * a + b * b + c * c)


@kernel
def all_scores(active, p, o, st, dmodel, ms, sel):
    """The 8 lobe selection scores s_k = |w_k E_k| (0 for inactive slots) as a tuple: the RGB
    length (SEL_LENGTH), the largest component (SEL_MAX) or 1 (SEL_UNIFORM).

    With w_k = L_k K_k (``layer_factors``) most reduce to constants of the material
    (``_pack_weights``): s_k = |L_k| E_k |K_k| for the lobes whose albedo is a scalar
    (specular, coat, fuzz; the thin-walled subsurface's QON factor), |L_k| |K_k e_k| for a
    constant colour e_k (transmission, subsurface), and for the diffuse lobe, whose albedo
    is rho e_g + rho_ms e_h (Eq. 20), |L_0| sqrt(|K rho|^2 e_g^2 + 2 (K rho).(K rho_ms) e_g e_h
    + |K rho_ms|^2 e_h^2) by length; only the metal lobe (and the diffuse one by max) is
    summed over channels."""
    E1s, E5s, E6s, Es, E1c, Ec, Ef, eg, eh, Eq = st
    L = layer_factors(p, o, st)
    uni = sel == SEL_UNIFORM
    mx = sel == SEL_MAX
    q = o + P_K
    m = 1 if mx else 0
    if mx:
        sd = _norm_or_max(True, p[q] * diffuse_albedo(dmodel, p[o + P_BASE_COLOR], p[o + P_RHO_MS], eg, eh),
                          p[q + 1] * diffuse_albedo(dmodel, p[o + P_BASE_COLOR + 1], p[o + P_RHO_MS + 1], eg, eh),
                          p[q + 2] * diffuse_albedo(dmodel, p[o + P_BASE_COLOR + 2], p[o + P_RHO_MS + 2], eg, eh))
    else:
        sd = math.sqrt(max(p[o + P_DQ] * eg * eg + 2.0 * p[o + P_DQ + 1] * eg * eh + p[o + P_DQ + 2] * eh * eh, 0.0))
    sm = 0.0
    if active & (1 << METAL):
        sm = _norm_or_max(mx, p[q + 6] * metal_albedo(p, o, 0, E1s, E5s, E6s, ms),
                          p[q + 7] * metal_albedo(p, o, 1, E1s, E5s, E6s, ms),
                          p[q + 8] * metal_albedo(p, o, 2, E1s, E5s, E6s, ms))
    c = o + P_SC + m
    s = (sd, Es * p[c + 2], sm, p[c + 6], p[c + 8] * (Eq if p[o + P_THIN] > 0.0 else 1.0), p[c + 10],
         Ec * p[c + 12], Ef * p[c + 14])
    return (_score_of(0, active, uni, L, s), _score_of(1, active, uni, L, s), _score_of(2, active, uni, L, s),
            _score_of(3, active, uni, L, s), _score_of(4, active, uni, L, s), _score_of(5, active, uni, L, s),
            _score_of(6, active, uni, L, s), _score_of(7, active, uni, L, s))


@kernel
def _score_of(k, active, uni, L, s):
    if not active & (1 << k):
        return 0.0
    return 1.0 if uni else abs(L[k]) * s[k]


@kernel
def probability(sk, S, K):
    """P_k = s_k / S; 1/K when every score is 0 (black surface: any distribution will do)."""
    return sk / S if S > 0.0 else 1.0 / K


@kernel
def active_count(active):
    """K: the number of active lobe slots."""
    K = 0
    for k in range(N_LOBES):
        K += 1 if active & (1 << k) else 0
    return K


# --------------------------------------------------------------------------- drivers


def _lobes_drive(active, dmodel, sel, ms, p, ps, wo, W, E, P):
    """W, E (n*8*3), P (n*8): weight, albedo and probability of every lobe slot."""
    n = wo.shape[0] // 3
    for i in prange(n):
        j = _U(i) * _U(3)
        o = _U(i) * _U(ps)
        oz = _F(wo[j + _U(2)])
        mu = min(max(oz, 0.0), 1.0)
        st = row_state(p, o, mu, dmodel, ms)
        up = oz > 0.0
        w0, w1, w2, e0, e1, e2 = weights_albedos_rgb(p, o, st, dmodel, ms)
        ss = all_scores(active, p, o, st, dmodel, ms, sel)
        S = 0.0
        K = 0
        for k in range(N_LOBES):
            b = (_U(i) * _U(N_LOBES) + _U(k))
            for c in range(3):
                W[b * _U(3) + _U(c)] = 0.0
                E[b * _U(3) + _U(c)] = 0.0
            P[b] = 0.0
            if active & (1 << k):
                W[b * _U(3)], W[b * _U(3) + _U(1)], W[b * _U(3) + _U(2)] = w0[k], w1[k], w2[k]
                # below the horizon nothing is reflected: E = 0 (and the probabilities uniform,
                # SEL_UNIFORM's as well)
                if up:
                    E[b * _U(3)], E[b * _U(3) + _U(1)], E[b * _U(3) + _U(2)] = e0[k], e1[k], e2[k]
                s = ss[k] if up else 0.0
                P[b] = s
                S += s
                K += 1
        for k in range(N_LOBES):
            b = _U(i) * _U(N_LOBES) + _U(k)
            if active & (1 << k):
                P[b] = probability(P[b], S, K)


def _albedo_drive(active, dmodel, ms, p, ps, wo, out):
    n = wo.shape[0] // 3
    for i in prange(n):
        j = _U(i) * _U(3)
        o = _U(i) * _U(ps)
        oz = _F(wo[j + _U(2)])
        mu = min(max(oz, 0.0), 1.0)
        st = row_state(p, o, mu, dmodel, ms)
        a0 = a1 = a2 = 0.0
        if oz > 0.0:
            w0, w1, w2, e0, e1, e2 = weights_albedos_rgb(p, o, st, dmodel, ms)
            for k in range(N_LOBES):
                if active & (1 << k):
                    a0 += w0[k] * e0[k]
                    a1 += w1[k] * e1[k]
                    a2 += w2[k] * e2[k]
        out[j] = a0
        out[j + _U(1)] = a1
        out[j + _U(2)] = a2


def _eval_drive(active, only, dmodel, ms, p, ps, wi, wo, out):
    """out (n*3) = sum_k w_k f_k, or the unweighted f_only when only >= 0."""
    n = wo.shape[0] // 3
    for i in prange(n):
        j = _U(i) * _U(3)
        o = _U(i) * _U(ps)
        ix, iy, iz = _F(wi[j]), _F(wi[j + _U(1)]), _F(wi[j + _U(2)])
        ox, oy, oz = _F(wo[j]), _F(wo[j + _U(1)]), _F(wo[j + _U(2)])
        mu = min(max(oz, 0.0), 1.0)
        st = row_state(p, o, mu, dmodel, ms, False)
        a0 = a1 = a2 = 0.0
        m, c = 0.0, 0.0
        if uses_base_ggx(active):
            m, c = mf.reflection(ix, iy, iz, ox, oy, oz, p[o + P_ALPHA_S])
        if oz > 0.0:
            w0, w1, w2, _, _, _ = weights_albedos_rgb(p, o, st, dmodel, ms)
            for k in range(N_LOBES):
                if (active & (1 << k)) and (only < 0 or only == k):
                    f0, f1, f2 = lobe_f(k, p, o, st, ix, iy, iz, ox, oy, oz, dmodel, ms, m, c)
                    if only >= 0:
                        a0, a1, a2 = f0, f1, f2
                    else:
                        a0 += w0[k] * f0
                        a1 += w1[k] * f1
                        a2 += w2[k] * f2
        out[j] = a0
        out[j + _U(1)] = a1
        out[j + _U(2)] = a2


#: The lobe slots the pdf and sample drivers loop over, a constant of each build: the base
#: lobes (diffuse, specular, metal: the first BASE_SLOTS slots), or all of them.  With the
#: bound fixed, LLVM unrolls the lobe loops and folds each lobe's switch; a base surface's
#: sample measured 15 % faster with 3 slots than with 8 (serial builds, interleaved).
BASE_SLOTS = 3


def slots_of(active):
    """The slot bound of the drivers that serve the lobe mask ``active``."""
    return BASE_SLOTS if active < (1 << BASE_SLOTS) else N_LOBES


def _pdf_driver(NL):
    """The pdf driver over the first NL lobe slots."""
    def _pdf_drive(active, dmodel, sel, ms, vndf, p, ps, wo, wi, out):
        """out (n) = sum_k P_k pdf_k(wi | wo)."""
        n = wo.shape[0] // 3
        for i in prange(n):
            j = _U(i) * _U(3)
            o = _U(i) * _U(ps)
            ix, iy, iz = _F(wi[j]), _F(wi[j + _U(1)]), _F(wi[j + _U(2)])
            ox, oy, oz = _F(wo[j]), _F(wo[j + _U(1)]), _F(wo[j + _U(2)])
            mu = min(max(oz, 0.0), 1.0)
            q = 0.0
            if oz > 0.0:
                # one pass: sum_k s_k pdf_k / sum_k s_k (uniform over the active lobes when every
                # score is 0), the mixture pdf with P_k = s_k / sum s
                st = row_state(p, o, mu, dmodel, ms)
                num = 0.0
                pdf_s = 0.0
                if uses_base_ggx(active):
                    pdf_s = mf.reflection_pdf(ix, iy, iz, ox, oy, oz, p[o + P_ALPHA_S], vndf)
                ss = all_scores(active, p, o, st, dmodel, ms, sel)
                S = 0.0
                flat = 0.0
                K = 0
                for k in range(NL):
                    if active & (1 << k):
                        pk = lobe_pdf(k, p, o, ix, iy, iz, ox, oy, oz, dmodel, vndf, pdf_s)
                        num += ss[k] * pk
                        S += ss[k]
                        flat += pk
                        K += 1
                q = num / S if S > 0.0 else flat / K
            out[i] = q
    return _pdf_drive


def _sample_driver(NL):
    """The sample driver over the first NL lobe slots."""
    def _sample_drive(active, dmodel, sel, ms, vndf, p, ps, wo, u, wi, out):
        """Pick lobe k with P_k (u[0]), sample it (u[1:3], or u[0] rescaled and u[1] when u has
        2 columns); wi (n*3), out (n) = the mixture pdf, with the chosen lobe's own pdf from its
        sampler (outside ``GGX_LOBES``); 0 marks a failed sample."""
        n = wo.shape[0] // 3
        ud = u.shape[0] // n
        K = active_count(active)
        for i in prange(n):
            j = _U(i) * _U(3)
            o = _U(i) * _U(ps)
            ju = _U(i) * _U(ud)
            ox, oy, oz = _F(wo[j]), _F(wo[j + _U(1)]), _F(wo[j + _U(2)])
            mu = min(max(oz, 0.0), 1.0)
            st = row_state(p, o, mu, dmodel, ms)
            ss = all_scores(active, p, o, st, dmodel, ms, sel)
            S = 0.0
            for k in range(NL):
                S += ss[k]
            u0 = _F(u[ju])
            # choose the lobe: the first whose cumulative probability exceeds u0
            chosen = -1
            last = -1
            lo = 0.0
            Pc = 0.0
            for k in range(NL):
                if active & (1 << k):
                    last = k
                    if chosen < 0:
                        Pk = probability(ss[k], S, K)
                        if u0 < lo + Pk:
                            chosen = k
                            Pc = Pk
                        else:
                            lo += Pk
            if chosen < 0:   # rounding left the CDF's end below u0
                chosen = last
                Pc = probability(ss[last], S, K)
            if ud == 3:
                u1, u2 = _F(u[ju + _U(1)]), _F(u[ju + _U(2)])
            else:
                u1 = min(max((u0 - lo) / Pc, 0.0), U_MAX) if Pc > 0.0 else 0.0
                u2 = _F(u[ju + _U(1)])
            x, y, z, own, ok = lobe_sample(chosen, p, o, ox, oy, oz, u1, u2, dmodel, vndf)
            ggx = (GGX_LOBES & (1 << chosen)) != 0
            q = 0.0
            if oz > 0.0 and ok and (ggx or own > 0.0):
                pdf_s = 0.0
                if uses_base_ggx(active):
                    pdf_s = mf.reflection_pdf(x, y, z, ox, oy, oz, p[o + P_ALPHA_S], vndf)
                mine = 0.0
                for k in range(NL):
                    if active & (1 << k):
                        Pk = probability(ss[k], S, K)
                        if k == chosen and not ggx:
                            q += Pk * own
                        elif Pk > 0.0 or k == chosen:
                            pk = lobe_pdf(k, p, o, x, y, z, ox, oy, oz, dmodel, vndf, pdf_s)
                            q += Pk * pk
                            mine = pk if k == chosen else mine
                if ggx and not mine > 0.0:   # the GGX lobe's own pdf: 0 marks a failed sample
                    q = 0.0
            if not oz > 0.0:
                x, y, z = 0.0, 0.0, 1.0
            wi[j] = x
            wi[j + _U(1)] = y
            wi[j + _U(2)] = z
            out[i] = q
    return _sample_drive


PDF_DRIVES = {nl: _pdf_driver(nl) for nl in (BASE_SLOTS, N_LOBES)}
SAMPLE_DRIVES = {nl: _sample_driver(nl) for nl in (BASE_SLOTS, N_LOBES)}


# --------------------------------------------------------------------------- batch calls

#: Below this many rows the serial build of a driver runs: waking the thread pool costs
#: more than a small batch (a single material's lobes(wo) is the common case).
SERIAL_ROWS = 4096
_serial = numba.njit(cache=True, fastmath=FASTMATH, error_model="numpy")


def serial_build(f):
    """The serial build of driver f, compiled from a copy of f named ``<name>_serial``.

    numba's disk cache files a function under its module, qualified name and first line,
    and keys its entries by signature and CPU only, not by the compile options: a serial and
    a parallel build of the same function share one entry, and whichever a process compiled
    first is loaded for both.  (So it was: after a process had evaluated one row, every
    later process's 10^6-row call ran the serial code on one thread.)"""
    g = types.FunctionType(f.__code__, f.__globals__, f.__name__ + "_serial", f.__defaults__, f.__closure__)
    g.__qualname__ = f.__qualname__ + "_serial"
    g.__module__ = f.__module__
    g.__doc__ = f.__doc__
    return _serial(g)


_DRIVERS = {f: (compiled(f), serial_build(f))
            for f in (_lobes_drive, _albedo_drive, _eval_drive, *PDF_DRIVES.values(), *SAMPLE_DRIVES.values())}


def _driver(f, n):
    parallel, serial = _DRIVERS[f]
    return serial if n < SERIAL_ROWS else parallel


@functools.cache
def tables():
    """(C, R): the padded GGX albedo tables (``microfacet.tables.padded_tables``), read by
    ``pack_drive`` only: it collapses them per material into the P_CURVE_* and P_E* curves
    in mu that the per-row drivers interpolate."""
    from ..microfacet.tables import padded_tables

    C, R = padded_tables()
    if R.shape[2] != N_CURVE or C.shape[1] != N_CCURVE:   # the parameter layout reserves them
        raise RuntimeError(f"GGX albedo tables have {R.shape[2] - 2} and {C.shape[1] - 2} mu nodes; the "
                           f"parameter layout expects {N_CURVE - 2} (N_CURVE) and {N_CCURVE - 2} (N_CCURVE)")
    return C, R


def _run(f, head, params, lead, dirs, outs):
    """Run driver f over the rows of ``lead``: ``params`` is one material (stride 0, never
    copied or tiled) or materials broadcasting to ``lead`` (stride N_PARAMS, expanded)."""
    n = math.prod(lead)
    if n == 0:
        return
    if params.ndim == 1 and n == 1:   # one material, one row (lobes(wo) of a material): no batch machinery
        _DRIVERS[f][1](*head, params, 0, *(rows(d, lead, k)[0] for d, k in dirs), *(o for o, _ in outs))
        return
    if params.ndim == 1:
        inputs = []
        for d, k in dirs:
            b, t = rows(d, lead, k)
            inputs.append((b, k, t))
        launch(_driver(f, n), head + (params, 0), inputs, outs, n)
        return
    p = np.ascontiguousarray(np.broadcast_to(params, lead + (N_PARAMS,))).reshape(-1)
    full = [np.ascontiguousarray(np.broadcast_to(d, lead + (k,))).reshape(-1) for d, k in dirs]
    _driver(f, n)(*head, p, N_PARAMS, *full, *(o for o, _ in outs))


def lobes_rows(flags, params, wo, lead):
    """(W (..., 8, 3), E (..., 8, 3), P (..., 8)) for float64 arrays broadcasting to ``lead``."""
    n = math.prod(lead)
    W = np.empty(n * N_LOBES * 3)
    E = np.empty(n * N_LOBES * 3)
    P = np.empty(n * N_LOBES)
    _run(_lobes_drive, (flags.active, flags.dmodel, flags.sel, flags.ms), params, lead, [(wo, 3)],
         [(W, N_LOBES * 3), (E, N_LOBES * 3), (P, N_LOBES)])
    return W.reshape(lead + (N_LOBES, 3)), E.reshape(lead + (N_LOBES, 3)), P.reshape(lead + (N_LOBES,))


def albedo_rows(flags, params, wo, lead):
    out = np.empty(math.prod(lead) * 3)
    _run(_albedo_drive, (flags.active, flags.dmodel, flags.ms), params, lead, [(wo, 3)], [(out, 3)])
    return out.reshape(lead + (3,))


def eval_rows(flags, params, wi, wo, lead, only=-1):
    out = np.empty(math.prod(lead) * 3)
    _run(_eval_drive, (flags.active, only, flags.dmodel, flags.ms), params, lead, [(wi, 3), (wo, 3)],
         [(out, 3)])
    return out.reshape(lead + (3,))


def pdf_rows(flags, params, wo, wi, lead):
    out = np.empty(math.prod(lead))
    _run(PDF_DRIVES[slots_of(flags.active)], (flags.active, flags.dmodel, flags.sel, flags.ms, flags.vndf), params, lead,
         [(wo, 3), (wi, 3)], [(out, 1)])
    return out.reshape(lead)


def sample_rows(flags, params, wo, u, lead):
    n = math.prod(lead)
    wi = np.empty(n * 3)
    out = np.empty(n)
    _run(SAMPLE_DRIVES[slots_of(flags.active)], (flags.active, flags.dmodel, flags.sel, flags.ms, flags.vndf), params, lead,
         [(wo, 3), (u, u.shape[-1])], [(wi, 3), (out, 1)])
    return wi.reshape(lead + (3,)), out.reshape(lead)
