"""The compiled lobes of ``OpenPBRSurface`` assembled from the lobe registry (``lobes``), and
the packing of a material's inputs into its parameter row.

Each lobe is a module of ``nodes.lobes`` holding its verbs together (pbrt-v4's ``BxDF``
shape): its BSDF, pdf, sampler, albedo, selection score and layer.  This module builds, from
the registry, the per-lobe part of the parameter layout (``LOBE_PARAM``) and the dispatch of
every verb by lobe id (``lobes.dispatch``: generated, one entry per registry row):
``lobe_f`` (k a compile-time constant), ``lobe_pdf``, ``lobe_albedo``, ``lobe_score``,
``layer_factor``, ``sampler_of``, ``lobe_sample``.  Each weight is a layer factor of mu_o
times a colour of the material, w_k[c] = L_k(mu_o) K_k[c], so that the selection scores are
constants of the material times functions of mu_o.  No input is checked here: the public
class checks its inputs once, at construction and on each call's directions.

The batch drivers (``_surface_drivers``) call these one lobe at a time over blocks of rows
(``_surface_passes``), with the lobe id a constant: each kernel folds to one lobe's formula,
and the kernels branch on directions only through selects, so the loops vectorise.
"""

import math

from .._jit import block, by_constant, opaque, pointer_of, serial
from ..microfacet import fresnel
from ..microfacet import kernels as mf
from ..microfacet.sheen import sheen_albedo_fit
from ..microfacet.tables import R_AXIS, X_AXIS, catmull_rom_at, node_at
from ..models.eon import eon_albedo_fit, rho_ms
from ..models.fon import E_F_avg
from ..models.qon import qon_AB
from ..sampling.mis import pow_tenth
from . import _surface_params as _params
from . import lobes as _registry
from ._surface_params import (
    N_CCURVE,
    N_CURVE,
    N_FIXED,
    ON_TOP,
    PARAM,
    PARAMS,
    SEL_MAX,
    SEL_UNIFORM,
    UNDER_COAT,
    UNDER_FUZZ,
    UNDER_SPECULAR,
    layout,
)
from .lobes import SAMPLERS
from .surface_inputs import packed_inputs

LOBES = tuple(_registry.REGISTRY)
N_LOBES = len(LOBES)
LOBE_NAMES = tuple(m.NAME for m in LOBES)
#: lobe ids of the built-in lobes (slots), by name
DIFFUSE, SPECULAR, METAL, TRANSMISSION, SUBSURFACE, SUBSURFACE_T, COAT, FUZZ = (
    LOBE_NAMES.index(n)
    for n in ("diffuse", "specular", "metal", "transmission", "subsurface", "subsurface_transmission", "coat", "fuzz")
)

#: The inputs of the nodedef that a registered lobe reads as they are (its ``INPUTS``, none
#: for the built-in lobes, whose inputs are derived by ``pack_drive``), in registry order.
LOBE_INPUTS = tuple(n for m in LOBES for n in getattr(m, "INPUTS", ()))
#: The per-lobe part of a surface row, after the fixed part (``PARAM``): every lobe's weight
#: colour K_k[c] (``weight_color``), its score constants |K_k e_k| and
#: max_c |K_k[c] e_k[c]| (e_k its ``constant_albedo``), and the lobes' own inputs.
LOBE_PARAMS = (("WEIGHT_COLOR", 3 * N_LOBES), ("SCORE_CONSTANT", 2 * N_LOBES))
LOBE_PARAM, _END = layout("LobeParam", LOBE_PARAMS, N_FIXED)
_LOBE_INPUT_FIELDS = tuple((n, w) for n, w in packed_inputs(LOBE_INPUTS) if n in LOBE_INPUTS)
#: offsets of the lobes' own inputs in a surface row (``p[offset + LOBE_INPUT.name]``)
LOBE_INPUT, N_PARAMS = layout("LobeInput", _LOBE_INPUT_FIELDS, _END)
ALL_PARAMS = PARAMS + LOBE_PARAMS + _LOBE_INPUT_FIELDS
for _m in LOBES:  # a lobe with inputs of its own reads them at p[offset + INPUT.<name>]
    if getattr(_m, "INPUTS", ()):
        setattr(_m, "INPUT", LOBE_INPUT)  # noqa: B010  (a module attribute mypy does not know)
N_LOBE_INPUT_VALUES = N_PARAMS - _END
# the table lookup and the offsets the table-lookup tests pass to it
layer_albedos = _params.layer_albedos
P_X_S, P_X_C, P_CURVE_S, P_CURVE_C = PARAM.X_S, PARAM.X_C, PARAM.CURVE_S, PARAM.CURVE_C
P_E1S, P_E5S, P_E6S, P_E1C = PARAM.E1S, PARAM.E5S, PARAM.E6S, PARAM.E1C

# --------------------------------------------------------------------------- packing
#: The material's packed inputs (``surface_inputs.packed_inputs``: float64, colours 3 wide),
#: in this order, are packed into the parameter layout by ``pack_drive``, once per material.
RAW = packed_inputs(LOBE_INPUTS)
INPUT, N_RAW = layout("Input", RAW)
#: the lobes' own inputs close the packed row; they are copied as they are
_RAW_LOBE_INPUTS = N_RAW - N_LOBE_INPUT_VALUES
#: The parameters that are the material's inputs as they are: (PARAM offset, INPUT offset,
#: width), copied by ``pack_drive``.
_COPIED = (
    (PARAM.BASE_COLOR, INPUT.base_color, 3),
    (PARAM.SPEC_COLOR, INPUT.specular_color, 3),
    (PARAM.SSS_COLOR, INPUT.subsurface_color, 3),
    (PARAM.FUZZ_COLOR, INPUT.fuzz_color, 3),
    (PARAM.R_DIFF, INPUT.base_diffuse_roughness, 1),
    (PARAM.BASE_WEIGHT, INPUT.base_weight, 1),
    (PARAM.METAL, INPUT.base_metalness, 1),
    (PARAM.SPEC_WEIGHT, INPUT.specular_weight, 1),
    (PARAM.TRANS_W, INPUT.transmission_weight, 1),
    (PARAM.SSS_W, INPUT.subsurface_weight, 1),
    (PARAM.SSS_ANISO, INPUT.subsurface_scatter_anisotropy, 1),
    (PARAM.COAT_W, INPUT.coat_weight, 1),
    (PARAM.FUZZ_W, INPUT.fuzz_weight, 1),
    (PARAM.FUZZ_R, INPUT.fuzz_roughness, 1),
    (PARAM.THIN, INPUT.geometry_thin_walled, 1),
    (_END, _RAW_LOBE_INPUTS, N_LOBE_INPUT_VALUES),  # the lobes' own inputs
)
#: warning bits of ``pack_drive``
W_SPEC_TIR, W_COAT_TIR, W_F82_NEGATIVE = 1, 2, 4

# --------------------------------------------------------------------------- dispatch
_M = __name__
#: K_k[c] of lobe k
weight_color = _registry.dispatch("weight_color", ("k", "p", "offset", "c"), [m.weight_color for m in LOBES], _M)
constant_albedo = _registry.dispatch(
    "constant_albedo", ("k", "p", "offset", "c"), [m.constant_albedo for m in LOBES], _M
)
is_on = _registry.dispatch("is_on", ("k", "p", "offset"), [m.is_on for m in LOBES], _M)
#: ``lobe_pdf(k, p, offset, d, dmodel, vndf, ggx_pdf)``: solid-angle pdf of lobe k's sampler
#: producing wi given wo (wo above the horizon); ``ggx_pdf``: the GGX reflection pdf at the
#: base specular's alpha (computed once a row for the specular and metal lobes)
lobe_pdf = _registry.dispatch(
    "lobe_pdf", ("k", "p", "offset", "d", "dmodel", "vndf", "ggx_pdf"), [m.pdf for m in LOBES], _M
)
#: ``lobe_albedo(k, c, p, offset, ms, st)``: E_k(wo) in channel c from the row's ``LayerState``
lobe_albedo = _registry.dispatch("lobe_albedo", ("k", "c", "p", "offset", "ms", "st"), [m.albedo for m in LOBES], _M)
_lobe_score = _registry.dispatch(
    "_lobe_score", ("k", "mx", "p", "offset", "weight_at", "constant", "ms", "st"), [m.score for m in LOBES], _M
)
sampler_of = _registry.dispatch("sampler_of", ("k", "dmodel"), [m.sampler for m in LOBES], _M)
sample_setup = _registry.dispatch(
    "sample_setup", ("k", "p", "offset"), [m.sample_setup for m in LOBES], _M, select=True
)
_sample_with = _registry.dispatch(
    "_sample_with", ("k", "p", "offset", "ox", "oy", "oz", "u1", "u2", "vndf", "width"), SAMPLERS, _M
)
_LAYER_NAMES = {UNDER_SPECULAR: "under_specular", UNDER_COAT: "under_coat", UNDER_FUZZ: "under_fuzz", ON_TOP: "1.0"}
#: ``lobe_f(k, p, offset, d, x)``, compiled code only, k a compile-time constant: lobe k's own
#: BSDF (f0, f1, f2), weight not applied; 0 outside the lobe's hemisphere (``Directions`` d,
#: ``EvalInputs`` x).  Branches on the directions are selects, so that a loop over rows
#: calling it for one lobe vectorises.
lobe_f = by_constant("lobe_f", ("k", "p", "offset", "d", "x"), [m.eval for m in LOBES], _M)


def _layer_factor_source():
    lines = ["def layer_factor(k, under_specular, under_coat, under_fuzz):"]
    for k, m in enumerate(LOBES):
        lines += [f"    if k == {k}:", f"        return {_LAYER_NAMES[m.LAYER]}"]
    return "\n".join(lines) + "\n    return 1.0\n"


def _layer_factor():
    namespace = {"__name__": _M}
    exec(compile(_layer_factor_source(), _registry.__file__, "exec"), namespace)
    f = namespace["layer_factor"]
    f.__doc__ = """L_k, the part of lobe k's weight that depends on wo: w_k[c] = L_k K_k[c], from
    its ``LAYER``.  Each layer passes 1 - weight E_layer(mu_o) of what lies beneath (albedo
    scaling): the fuzz (under_fuzz = 1 - F E_fuzz) over the coat (under_coat = under_fuzz
    (1 - C E_coat)) over the base, and the dielectric specular layer (under_specular =
    under_coat (1 - E_spec)) over transmission, subsurface and diffuse."""
    return block(f)


layer_factor = _layer_factor()


@block
def lobe_score(k, sel, p, offset, ms, L, st):
    """The selection score s_k = |w_k E_k| of lobe k (L = its ``layer_factor``; st: the row's
    ``LayerState``): by RGB length (SEL_LENGTH), largest component (SEL_MAX) or 1
    (SEL_UNIFORM).  With w_k = L_k K_k, most reduce to constants of the material
    (LOBE_PARAM.SCORE_CONSTANT) times scalars of mu_o (the lobe's ``score``)."""
    mx = sel == SEL_MAX
    by_length = p[offset + LOBE_PARAM.SCORE_CONSTANT + 2 * k]
    by_max = p[offset + LOBE_PARAM.SCORE_CONSTANT + 2 * k + 1]
    constant = by_max if mx else by_length
    s = _lobe_score(k, mx, p, offset, offset + LOBE_PARAM.WEIGHT_COLOR + 3 * k, constant, ms, st)
    return 1.0 if sel == SEL_UNIFORM else abs(L) * s


@block
def lobe_sample(sampler, k, p, offset, ox, oy, oz, u1, u2, vndf):
    """(x, y, z, ok): a direction from lobe k (a float: the row's chosen lobe) drawn by its
    ``sampler`` (a constant of the caller's loop; the lobe sets the sampler's width and the
    side of the surface, ``sample_setup``); ok is False when the sampler failed (a GGX NDF
    normal facing away from wo)."""
    width, side = sample_setup(k, p, offset)
    x, y, z, ok = _sample_with(sampler, p, offset, ox, oy, oz, u1, u2, vndf, width)
    return x, y, z * side, ok


@block
def uses_base_ggx(active):
    return (active & ((1 << SPECULAR) | (1 << METAL))) != 0


# --------------------------------------------------------------------------- packing


@block
def _axes(out, at, v, n, kind):
    """Node index and Catmull-Rom weights of v on a table axis, into out[at:at + 5]."""
    i, frac = node_at(v, n, kind)
    w0, w1, w2, w3 = catmull_rom_at(frac)
    out[at] = i
    out[at + 1] = w0
    out[at + 2] = w1
    out[at + 3] = w2
    out[at + 4] = w3


@block
def _table_axes(out, at, r, x, nCr, nRr, nRx):
    _axes(out, at, r, nCr, R_AXIS)
    _axes(out, at + 5, r, nRr, R_AXIS)
    _axes(out, at + 10, x, nRx, X_AXIS)


@block
def _curve(out, at, axes, R):
    """out[at + m] = the dielectric ratio table at the (roughness, x) of the axes at out[axes:]
    for every padded mu node m (the same tensor-product Catmull-Rom, summed over two axes)."""
    ir, ix = int(out[axes + 5]), int(out[axes + 10])
    for m in range(N_CURVE):
        v = 0.0
        for a in range(4):
            for b in range(4):
                v += out[axes + 6 + a] * out[axes + 11 + b] * R[ir + a, ix + b, m]
        out[at + m] = v


@block
def _conductor_curve(out, at, axes, C, c):
    """out[at + m] = basis albedo c of the conductor table at the roughness whose node and
    weights are out[axes:axes + 5], for every padded mu node m."""
    ir = int(out[axes])
    for m in range(N_CCURVE):
        out[at + m] = (
            out[axes + 1] * C[ir, m, c]
            + out[axes + 2] * C[ir + 1, m, c]
            + out[axes + 3] * C[ir + 2, m, c]
            + out[axes + 4] * C[ir + 3, m, c]
        )


@block
def _pack_layer(out, offset, ggx, tab, curve, r, x, nCr, nRr, nRx, RT):
    """A GGX layer's parameters from its roughness r and |sqrt(F0)| x of its modulated index:
    alpha, r, x and eta at out[offset + ggx:] (PARAM.ALPHA_*, R_*, X_*, ETA_*, in this
    order), its table axes (PARAM.TAB_*) and its collapsed dielectric curve (PARAM.CURVE_*)."""
    out[offset + ggx] = mf.alpha_of(r)
    out[offset + ggx + 1] = r
    out[offset + ggx + 2] = x
    out[offset + ggx + 3] = fresnel.eta_of_x(x)
    _table_axes(out, offset + tab, r, x, nCr, nRr, nRx)
    _curve(out, offset + curve, offset + tab, RT)


@block
def _pack_weights(out, offset):
    """The material part K_k[c] of every lobe's weight (LOBE_PARAM.WEIGHT_COLOR: each lobe's
    ``weight_color``, following the reference graph open_pbr_surface.mtlx), then the score
    constants (LOBE_PARAM.SCORE_CONSTANT, PARAM.DIFFUSE_SCORE) of ``lobe_score``."""
    for k in range(N_LOBES):
        n2 = 0.0
        mx = 0.0
        for c in range(3):
            w = weight_color(k, out, offset, c)
            out[offset + LOBE_PARAM.WEIGHT_COLOR + 3 * k + c] = w
            v = w * constant_albedo(k, out, offset, c)
            n2 += v * v
            mx = max(mx, abs(v))
        out[offset + LOBE_PARAM.SCORE_CONSTANT + 2 * k] = math.sqrt(n2)
        out[offset + LOBE_PARAM.SCORE_CONSTANT + 2 * k + 1] = mx
    a = b = d = 0.0
    w = offset + LOBE_PARAM.WEIGHT_COLOR + 3 * DIFFUSE
    for c in range(3):
        x = out[w + c] * out[offset + PARAM.BASE_COLOR + c]
        y = out[w + c] * out[offset + PARAM.RHO_MS + c]
        a += x * x
        b += x * y
        d += y * y
    out[offset + PARAM.DIFFUSE_SCORE] = a
    out[offset + PARAM.DIFFUSE_SCORE + 1] = b
    out[offset + PARAM.DIFFUSE_SCORE + 2] = d


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
        at = i * N_RAW
        offset = i * N_PARAMS
        for dst, src, width in _COPIED:
            for c in range(width):
                out[offset + dst + c] = raw[at + src + c]
        bw, M, sw = raw[at + INPUT.base_weight], raw[at + INPUT.base_metalness], raw[at + INPUT.specular_weight]
        r_s, ior = raw[at + INPUT.specular_roughness], raw[at + INPUT.specular_ior]
        S = raw[at + INPUT.subsurface_weight]
        C, r_c, c_ior, c_dark = (
            raw[at + INPUT.coat_weight],
            raw[at + INPUT.coat_roughness],
            raw[at + INPUT.coat_ior],
            raw[at + INPUT.coat_darkening],
        )
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
        k_coat = 1.0 - (1.0 - fresnel.f0(c_ior)) / (c_ior * c_ior)
        for c in range(3):
            bc = raw[at + INPUT.base_color + c]
            sc = raw[at + INPUT.specular_color + c]
            F0 = bw * bc
            out[offset + PARAM.METAL_F0 + c] = F0
            am = fresnel.f82_a(F0, sc)
            out[offset + PARAM.METAL_A + c] = am
            if M > 0.0 and sw > 0.0:
                for k in range(257):
                    if fresnel.f82(k / 256.0, F0, am) < 0.0:
                        warn |= W_F82_NEGATIVE
            out[offset + PARAM.TRANS_TINT + c] = (
                1.0 if raw[at + INPUT.transmission_depth] > 0.0 else raw[at + INPUT.transmission_color + c]
            )
            ssc = raw[at + INPUT.subsurface_color + c]
            # base darkening and coat attenuation [Kcoat, Ebase, base_darkening, coat_attenuation]
            E_base = (1.0 - M) * ((1.0 - S) * bc + S * ssc) + M * bc * sw
            dark = (1.0 - k_coat) / (1.0 - E_base * k_coat)
            out[offset + PARAM.BASE_MUL + c] = (1.0 + C * c_dark * (dark - 1.0)) * (
                1.0 + C * (raw[at + INPUT.coat_color + c] - 1.0)
            )
        out[offset + PARAM.R_TENTH] = pow_tenth(raw[at + INPUT.base_diffuse_roughness])
        avg = E_F_avg(raw[at + INPUT.base_diffuse_roughness])
        for c in range(3):
            out[offset + PARAM.RHO_MS + c] = rho_ms(raw[at + INPUT.base_color + c], avg)
        out[offset + PARAM.SHEEN_FIT], out[offset + PARAM.SHEEN_FIT + 1], out[offset + PARAM.SHEEN_FIT + 2] = (
            sheen_albedo_fit(raw[at + INPUT.fuzz_roughness])
        )
        out[offset + PARAM.EON_FIT], out[offset + PARAM.EON_FIT + 1], out[offset + PARAM.EON_FIT + 2] = eon_albedo_fit(
            raw[at + INPUT.base_diffuse_roughness]
        )
        out[offset + PARAM.QON_AB], out[offset + PARAM.QON_AB + 1] = qon_AB(
            raw[at + INPUT.base_diffuse_roughness], 0.33
        )
        _pack_layer(out, offset, PARAM.ALPHA_S, PARAM.TAB_S, PARAM.CURVE_S, r_eff, x, nCr, nRr, nRx, RT)
        _pack_layer(out, offset, PARAM.ALPHA_C, PARAM.TAB_C, PARAM.CURVE_C, r_c, xc, nCr, nRr, nRx, RT)
        _conductor_curve(out, offset + PARAM.E1S, offset + PARAM.TAB_S, CT, opaque(0))
        _conductor_curve(out, offset + PARAM.E5S, offset + PARAM.TAB_S, CT, opaque(1))
        _conductor_curve(out, offset + PARAM.E6S, offset + PARAM.TAB_S, CT, opaque(2))
        _conductor_curve(out, offset + PARAM.E1C, offset + PARAM.TAB_C, CT, opaque(0))
        _pack_weights(out, offset)
        # the lobes that can be non-zero
        for k in range(N_LOBES):
            if is_on(k, out, offset):
                mask |= 1 << k
    return mask, warn


pack_drive = serial(_pack_drive)
