"""Block passes of the surface's drivers: loops over the rows of one block, one quantity or
one lobe at a time, so that each loop is straight-line code that LLVM vectorises.

A driver (``_surface_drivers``) walks its rows in blocks of ``B``; each block keeps its
per-row values in a scratch buffer ``f`` of ``NROWS`` rows of B float64 (``at(row, r)``):
the directions, the layer albedos of mu_o (``state_passes``), the selection probabilities
(``probability_pass``), then whatever the verb accumulates.  The lobe passes run once per
active lobe with the lobe id a compile-time constant (``lobe_loop``, the one loop over the
lobe ids), so ``lobe_f`` / ``lobe_pdf`` / ``lobe_sample`` fold to that lobe's formula and the
loop body has no switch; the material's options (multiple scattering, VNDF,
the selection rule) are selects, the diffuse model a constant of the runner that LLVM
folds into the diffuse lobe's pass once it is inlined there.
A loop with a run-time switch inside, or a libm call (``exp`` of the fuzz albedo), stays
scalar; measured on the 2-core test VM, the base surface's sample went from ~235 to ~60 ns
a row single-threaded with this layout (``tools/bench.py``).

Parameters: ``stride`` is the parameter stride, a compile-time constant of each driver build:
0 for one material (every load of p is then loop-invariant and hoisted), N_PARAMS for a
material per row (``par``).
"""

from .._jit import block, helper, opaque, unrolled
from .._launch import _U
from ..microfacet.sheen import sheen_albedo_at
from ..models.qon import qon_albedo
from ..sampling.simple import U_MAX
from ._surface_kernels import (
    COAT,
    FUZZ,
    LOBE_PARAM,
    LOBES,
    N_LOBES,
    SUBSURFACE,
    layer_factor,
    lobe_albedo,
    lobe_f,
    lobe_pdf,
    lobe_sample,
    lobe_score,
    sampler_of,
    uses_base_ggx,
)
from ._surface_params import (
    D_EON,
    N_SAMPLERS,
    PARAM,
    Directions,
    EvalInputs,
    LayerState,
    diffuse_albedo_terms,
    ggx_reflection,
    ggx_reflection_pdf,
    layer_albedos,
    layout,
)

#: Rows per block: a block's scratch (NROWS x B float64, 25 KB) stays in the L1 cache.
B = 64

#: The scratch rows of a block, each B float64 (``at(row, r)``): the per-row values a block's
#: passes hand to each other.
ROWS = (
    ("OX", 1), ("OY", 1), ("OZ", 1),  # wo
    ("IX", 1), ("IY", 1), ("IZ", 1),  # wi (given, or sampled)
    ("MU", 1),  # mu_o clamped to [0, 1]
    # the state of mu_o (``state_passes``)
    ("E1_SPECULAR", 1), ("E5_SPECULAR", 1), ("E6_SPECULAR", 1), ("E_SPECULAR", 1),  # GGX basis albedos, dielectric albedo of the base specular
    ("E1_COAT", 1), ("E_COAT", 1),  # E1 and the dielectric albedo of the coat (1, 0 without coat)
    ("E_FUZZ", 1),  # fuzz albedo (0 without fuzz)
    ("DIFFUSE_G", 1), ("DIFFUSE_H", 1),  # diffuse albedo terms, E = rho e_g + rho_ms e_h
    ("THIN_REFLECTION", 1),  # QON albedo of the thin-walled subsurface reflection (1 otherwise)
    ("UNDER_SPECULAR", 1), ("UNDER_COAT", 1), ("UNDER_FUZZ", 1),  # layer factors: under the specular layer, the base, under the fuzz
    ("A0", 1), ("A1", 1), ("A2", 1),  # RGB accumulators (eval, albedo)
    ("GGX_F", 1), ("GGX_COS", 1), ("GGX_PDF", 1),  # base specular GGX: f without Fresnel, wo.h; its pdf
    ("U0", 1), ("U1", 1), ("U2", 1),  # u: the lobe choice's, and the chosen lobe's sampler inputs
    ("OK", 1),  # 1 where the sampler succeeded
    ("CHOSEN", 1),  # the chosen lobe slot
    ("MIXTURE_PDF", 1),  # mixture pdf
    ("CHOSEN_PDF", 1),  # the chosen lobe's own pdf at the sample
    # one sampler's rows of OX..OZ, U1, U2, CH, gathered (``sample_pass``), and its samples,
    # before they are scattered to IX..IZ, OK
    ("TOX", 1), ("TOY", 1), ("TOZ", 1), ("TU1", 1), ("TU2", 1), ("T_LOBE", 1),
    ("TX", 1), ("TY", 1), ("TZ", 1), ("TOK", 1),
    ("PROBABILITY", N_LOBES),  # the selection probabilities P_k
)  # fmt: skip
ROW, NROWS = layout("Row", ROWS)


@helper
def at(row, r):
    """Index of entry r of scratch row ``row``."""
    return _U(row) * _U(B) + _U(r)


@helper
def span(m):
    """The rows the passes of a block of m rows run over: B for a whole block (a constant trip
    count), else m rounded up to the vector width (a short call, lobes(wo) of one row, does
    not pay for a block of B rows; the rows beyond m hold the padding of ``load_pass``)."""
    return B if m == B else (m + 3) // 4 * 4


@helper
def par(stride, first, r):
    """Offset of the parameters of row first + r: 0 for one material (stride = 0), else a row's own."""
    return _U(first + r) * _U(stride)


@helper
def active_count(active):
    """The number of active lobe slots."""
    count = 0
    for k in range(N_LOBES):
        count += 1 if active & (1 << k) else 0
    return count


@helper
def is_on(active, k):
    return (active & (1 << k)) != 0


# --------------------------------------------------------------------------- state of mu_o


@block
def load_pass(d, first, m, f, row):
    """Rows first .. first + m of the (n*3) direction buffer d into scratch rows row .. row + 2; the
    rest of the block (m < B: the last block) is padded with the normal, so that every other
    pass can run over ``span(m)`` rows, a multiple of the vector width."""
    for r in range(m):
        j = _U(3) * _U(first + r)
        f[at(row, r)] = d[j]
        f[at(row + 1, r)] = d[j + _U(1)]
        f[at(row + 2, r)] = d[j + _U(2)]
    for r in range(m, B):
        f[at(row, r)] = 0.0
        f[at(row + 1, r)] = 0.0
        f[at(row + 2, r)] = 1.0


@block
def load_u_pass(ud, u, first, m, f):
    """ROW.U0 = u[0] and, with 3 columns, ROW.U1, ROW.U2 = u[1], u[2]; with 2, ROW.U2 = u[1] (ROW.U1 is then u0
    rescaled, ``choose_pass``).  Padded with 1/2 beyond row m."""
    for r in range(m):
        j = _U(ud) * _U(first + r)
        f[at(ROW.U0, r)] = u[j]
        if ud == 3:
            f[at(ROW.U1, r)] = u[j + _U(1)]
            f[at(ROW.U2, r)] = u[j + _U(2)]
        else:
            f[at(ROW.U2, r)] = u[j + _U(1)]
    for r in range(m, B):
        f[at(ROW.U0, r)] = 0.5
        f[at(ROW.U1, r)] = 0.5
        f[at(ROW.U2, r)] = 0.5


@helper
def fill_pass(f, row, m, v):
    for r in range(m):
        f[at(row, r)] = v


@helper
def clear_rgb_pass(f, m):
    """ROW.A0..A2 = 0: the RGB accumulators of eval and albedo."""
    fill_pass(f, ROW.A0, m, 0.0)
    fill_pass(f, ROW.A1, m, 0.0)
    fill_pass(f, ROW.A2, m, 0.0)


@block
def state_passes(lobes, active, dmodel, ms, albedos, basis, p, stride, first, m, f):
    """The per-row values of mu_o shared by every lobe: the layer albedos (ROW.E1_SPECULAR, ROW.E_SPECULAR, and ROW.E5_SPECULAR,
    ROW.E6_SPECULAR when ``basis``; ROW.E1_COAT, ROW.E_COAT; ROW.E_FUZZ), the layer factors (ROW.UNDER_SPECULAR, ROW.UNDER_COAT, ROW.UNDER_FUZZ) and, when ``albedos``,
    the diffuse albedo terms (ROW.DIFFUSE_G, ROW.DIFFUSE_H) and ROW.THIN_REFLECTION.  Layers no material of the call has are filled
    with their neutral values instead of looked up (``lobes``: the runner's lobe set, a
    constant once inlined, so that a runner without coat or fuzz has no such loops)."""
    for r in range(m):
        f[at(ROW.MU, r)] = min(max(f[at(ROW.OZ, r)], 0.0), 1.0)
    for r in range(m):
        offset = par(stride, first, r)
        E1, E5, E6, E = layer_albedos(
            p, offset, PARAM.E1S, PARAM.E5S, PARAM.E6S, PARAM.CURVE_S, f[at(ROW.MU, r)], p[offset + PARAM.X_S], ms
        )
        f[at(ROW.E1_SPECULAR, r)] = E1
        f[at(ROW.E_SPECULAR, r)] = E
        if basis:
            f[at(ROW.E5_SPECULAR, r)] = E5
            f[at(ROW.E6_SPECULAR, r)] = E6
    if is_on(lobes, COAT) and is_on(active, COAT):
        for r in range(m):
            offset = par(stride, first, r)
            E1, _, _, E = layer_albedos(
                p, offset, PARAM.E1C, PARAM.E1C, PARAM.E1C, PARAM.CURVE_C, f[at(ROW.MU, r)], p[offset + PARAM.X_C], ms
            )
            on = p[offset + PARAM.COAT_W] > 0.0
            f[at(ROW.E1_COAT, r)] = E1 if on else 1.0
            f[at(ROW.E_COAT, r)] = E if on else 0.0
    else:
        fill_pass(f, ROW.E1_COAT, m, 1.0)
        fill_pass(f, ROW.E_COAT, m, 0.0)
    if is_on(lobes, FUZZ) and is_on(active, FUZZ):
        for r in range(m):
            offset = par(stride, first, r)
            E = sheen_albedo_at(
                f[at(ROW.MU, r)],
                p[offset + PARAM.SHEEN_FIT],
                p[offset + PARAM.SHEEN_FIT + 1],
                p[offset + PARAM.SHEEN_FIT + 2],
            )
            f[at(ROW.E_FUZZ, r)] = E if p[offset + PARAM.FUZZ_W] > 0.0 else 0.0
    else:
        fill_pass(f, ROW.E_FUZZ, m, 0.0)
    for r in range(m):
        offset = par(stride, first, r)
        Tf = 1.0 - p[offset + PARAM.FUZZ_W] * f[at(ROW.E_FUZZ, r)]
        Tb = Tf * (1.0 - p[offset + PARAM.COAT_W] * f[at(ROW.E_COAT, r)])
        f[at(ROW.UNDER_FUZZ, r)] = Tf
        f[at(ROW.UNDER_COAT, r)] = Tb
        f[at(ROW.UNDER_SPECULAR, r)] = Tb * (1.0 - f[at(ROW.E_SPECULAR, r)])
    if not albedos:
        return
    if dmodel == D_EON:  # EON's pass typed with the model a literal: LLVM vectorises it (38 % faster albedo)
        diffuse_albedo_pass(D_EON, p, stride, first, m, f)
    else:
        diffuse_albedo_pass(dmodel, p, stride, first, m, f)
    if (
        is_on(lobes, SUBSURFACE) and is_on(active, SUBSURFACE) and p[PARAM.THIN] > 0.0
    ):  # thin-walled is one value per surface
        for r in range(m):
            offset = par(stride, first, r)
            f[at(ROW.THIN_REFLECTION, r)] = qon_albedo(
                f[at(ROW.MU, r)], p[offset + PARAM.QON_AB], p[offset + PARAM.QON_AB + 1]
            )
    else:
        fill_pass(f, ROW.THIN_REFLECTION, m, 1.0)


@block
def diffuse_albedo_pass(dmodel, p, stride, first, m, f):
    for r in range(m):
        eg, eh = diffuse_albedo_terms(dmodel, p, par(stride, first, r), f[at(ROW.MU, r)])
        f[at(ROW.DIFFUSE_G, r)] = eg
        f[at(ROW.DIFFUSE_H, r)] = eh


@helper
def state_at(f, r):
    """The ``LayerState`` of row r, from the state rows of the scratch."""
    return LayerState(
        f[at(ROW.E1_SPECULAR, r)],
        f[at(ROW.E5_SPECULAR, r)],
        f[at(ROW.E6_SPECULAR, r)],
        f[at(ROW.E_SPECULAR, r)],
        f[at(ROW.E_COAT, r)],
        f[at(ROW.E_FUZZ, r)],
        f[at(ROW.DIFFUSE_G, r)],
        f[at(ROW.DIFFUSE_H, r)],
        f[at(ROW.THIN_REFLECTION, r)],
    )


@helper
def directions_at(f, r):
    """The ``Directions`` (wi, wo) of row r, from the scratch."""
    return Directions(
        f[at(ROW.IX, r)], f[at(ROW.IY, r)], f[at(ROW.IZ, r)], f[at(ROW.OX, r)], f[at(ROW.OY, r)], f[at(ROW.OZ, r)]
    )


@block
def albedo_of(k, c, p, offset, f, r, ms):
    """E_k in channel c at row r (``lobe_albedo`` on the state rows).  The diffuse albedo uses
    EON's form rho e_g + rho_ms e_h for every model: e_h = 0 for QON and Lambert."""
    return lobe_albedo(k, c, p, offset, ms, state_at(f, r))


@block
def factor_of(k, f, r):
    """L_k at row r (``layer_factor`` on the state rows)."""
    return layer_factor(k, f[at(ROW.UNDER_SPECULAR, r)], f[at(ROW.UNDER_COAT, r)], f[at(ROW.UNDER_FUZZ, r)])


@block
def score_pass(k, dmodel, sel, p, stride, first, m, f, ms):
    """ROW.PROBABILITY + k = s_k, the selection score of lobe slot k (``lobe_score``), at every row
    (dmodel: unused; the diffuse score uses EON's form of the albedo, as ``albedo_of``)."""
    for r in range(m):
        offset = par(stride, first, r)
        f[at(ROW.PROBABILITY + k, r)] = lobe_score(k, sel, p, offset, ms, factor_of(k, f, r), state_at(f, r))


def lobe_loop(name, pass_, literal):
    """``name(lobes, active, dmodel, *rest)``, compiled code only: ``pass_(k, dmodel, *rest)`` of
    every lobe slot k of the compile-time set ``lobes`` (a bit mask, the runner's) that the
    run-time mask ``active`` holds, in slot order -- the one dispatch skeleton of the lobe
    passes.  The slots outside ``lobes`` are not compiled at all.

    ``literal``: k is a literal constant of each call (the model passed through
    ``_jit.opaque``, D_EON for the slots other than the diffuse one, which ignore it): the
    pass is compiled once per lobe, folded to that lobe's formula (``eval``: without it LLVM
    did not vectorise the lobe loops), and once for every diffuse model.  Otherwise k and
    the model are passed through ``_jit.opaque``: the pass is compiled once, and LLVM folds
    the constants after inlining it into its driver."""
    code = pass_.py_func.__code__
    rest = code.co_varnames[2 : code.co_argcount]
    args = ", ".join(rest)

    def body(lobes):
        calls = []
        for k in range(N_LOBES):
            if lobes >> k & 1:
                if literal:
                    head = (
                        f"{k}, opaque(dmodel)" if getattr(LOBES[k], "READS_DIFFUSE_MODEL", False) else f"{k}, {D_EON}"
                    )
                else:
                    head = f"opaque({k}), opaque(dmodel)"
                calls.append(f"if active >> {k} & 1:\n    pass_({head}, {args})")
        return "\n".join(calls) or "return"

    return unrolled(name, ("lobes", "active", "dmodel", *rest), body, {"pass_": pass_, "opaque": opaque}, __name__)


each_score = lobe_loop("each_score", score_pass, literal=False)


@block
def probability_pass(lobes, active, sel, p, stride, first, m, f, ms):
    """PR + k: the selection probability P_k = s_k / sum_j s_j of every lobe slot k (uniform
    over the active slots when every score is 0 -- a black surface -- or wo is below the
    horizon; 0 for inactive slots).  One loop per active lobe's score (``each_score``), then
    one that normalises: each vectorises (one loop doing all of it does not)."""
    for k in range(N_LOBES):
        fill_pass(f, ROW.PROBABILITY + k, m, 0.0)
    each_score(lobes, active, D_EON, sel, p, stride, first, m, f, ms)
    flat = 1.0 / active_count(active)
    for r in range(m):
        S = 0.0
        for k in range(N_LOBES):
            S += f[at(ROW.PROBABILITY + k, r)]
        pos = (S > 0.0) & (f[at(ROW.OZ, r)] > 0.0)
        inv = 1.0 / S
        for k in range(N_LOBES):
            P = f[at(ROW.PROBABILITY + k, r)] * inv if pos else flat
            f[at(ROW.PROBABILITY + k, r)] = P if is_on(active, k) else 0.0


# --------------------------------------------------------------------------- lobes


@block
def ggx_pass(active, p, stride, first, m, f):
    """ROW.GGX_F, ROW.GGX_COS: the base specular's GGX reflection (without Fresnel) and wo.h, shared by the
    specular and metal lobes."""
    if not uses_base_ggx(active):
        return
    for r in range(m):
        offset = par(stride, first, r)
        g, c = ggx_reflection(directions_at(f, r), p[offset + PARAM.ALPHA_S])
        f[at(ROW.GGX_F, r)] = g
        f[at(ROW.GGX_COS, r)] = c


@block
def ggx_pdf_pass(active, vndf, p, stride, first, m, f):
    """ROW.GGX_PDF: the base specular's GGX reflection pdf at wi (specular and metal lobes)."""
    if not uses_base_ggx(active):
        return
    for r in range(m):
        offset = par(stride, first, r)
        f[at(ROW.GGX_PDF, r)] = ggx_reflection_pdf(directions_at(f, r), p[offset + PARAM.ALPHA_S], vndf)


@block
def eval_lobe_pass(k, dmodel, weighted, ms, p, stride, first, m, f):
    """ROW.A0..A2 += w_k f_k, or f_k unweighted (``weighted`` False: one lobe's own BSDF, added
    to zeros), at every row of the block."""
    for r in range(m):
        offset = par(stride, first, r)
        d = directions_at(f, r)
        x = EvalInputs(
            opaque(dmodel),
            ms,
            f[at(ROW.GGX_F, r)],
            f[at(ROW.GGX_COS, r)],
            f[at(ROW.E1_SPECULAR, r)],
            f[at(ROW.E1_COAT, r)],
            f[at(ROW.E_FUZZ, r)],
        )
        f0, f1, f2 = lobe_f(k, p, offset, d, x)
        L = factor_of(opaque(k), f, r)
        w = offset + LOBE_PARAM.WEIGHT_COLOR + 3 * k
        f[at(ROW.A0, r)] += (L * p[w] if weighted else 1.0) * f0
        f[at(ROW.A1, r)] += (L * p[w + 1] if weighted else 1.0) * f1
        f[at(ROW.A2, r)] += (L * p[w + 2] if weighted else 1.0) * f2


@block
def pdf_lobe_pass(k, dmodel, track, vndf, p, stride, first, m, f):
    """ROW.MIXTURE_PDF += P_k pdf_k(wi | wo) (a lobe with P_k = 0 adds nothing, whatever its pdf); when
    ``track``, ROW.CHOSEN_PDF = pdf_k on the rows that chose lobe k."""
    for r in range(m):
        offset = par(stride, first, r)
        d = directions_at(f, r)
        pk = lobe_pdf(k, p, offset, d, dmodel, vndf, f[at(ROW.GGX_PDF, r)])
        P = f[at(ROW.PROBABILITY + k, r)]
        f[at(ROW.MIXTURE_PDF, r)] += P * pk if P > 0.0 else 0.0
        if track:
            f[at(ROW.CHOSEN_PDF, r)] = pk if f[at(ROW.CHOSEN, r)] == k else f[at(ROW.CHOSEN_PDF, r)]


@block
def choose_pass(ud, m, f):
    """ROW.CHOSEN: the lobe whose interval of the CDF (slot order) holds u0 (ROW.U0); ROW.U1: its sampler's
    first input, u[1] (ud = 3, loaded) or u0 rescaled within the chosen interval,
    (u0 - C_{k-1})/P_k (ud = 2).  A u0 that rounding leaves above the CDF's end picks the
    last slot with P_k > 0."""
    for r in range(m):
        u0 = f[at(ROW.U0, r)]
        lo = 0.0
        chosen = -1.0
        Pc = 0.0
        last = 0.0
        Plast = 0.0
        lolast = 0.0
        for k in range(N_LOBES):  # a constant bound: unrolled, branch-free
            Pk = f[at(ROW.PROBABILITY + k, r)]
            hit = (chosen < 0.0) & (u0 < lo + Pk)
            pos = Pk > 0.0
            lolast = lo if pos else lolast
            last = float(k) if pos else last
            Plast = Pk if pos else Plast
            Pc = Pk if hit else Pc
            lo = lo if (hit | (chosen >= 0.0)) else lo + Pk
            chosen = float(k) if hit else chosen
        miss = chosen < 0.0
        f[at(ROW.CHOSEN, r)] = last if miss else chosen
        Pc = Plast if miss else Pc
        lo = lolast if miss else lo
        if ud == 2:
            f[at(ROW.U1, r)] = min(max((u0 - lo) / Pc, 0.0), U_MAX)


@block
def compact(dmodel, m, f, idx, cnt):
    """idx[s B : s B + cnt[s]]: the rows of the block whose chosen lobe is drawn by sampler s
    (``sampler_of``), in order."""
    for s in range(N_SAMPLERS):
        cnt[s] = 0
    for r in range(m):
        s = sampler_of(int(f[at(ROW.CHOSEN, r)]), dmodel)
        idx[_U(s) * _U(B) + _U(cnt[s])] = r
        cnt[s] += 1


@block
def sample_pass(sampler, vndf, p, stride, first, f, idx, cnt):
    """ROW.IX..IZ, ROW.OK of the rows drawn by ``sampler``: their lobes' samples at (ROW.U1, ROW.U2).  The
    rows' inputs are gathered into contiguous scratch rows, sampled there (a vectorised
    loop; with stores to rows listed in ``idx`` it would not be, as LLVM cannot rule out
    repeats), and the samples scattered back."""
    c = cnt[sampler]
    lst = _U(sampler) * _U(B)
    for t in range(c):
        r = idx[lst + _U(t)]
        f[at(ROW.TOX, t)] = f[at(ROW.OX, r)]
        f[at(ROW.TOY, t)] = f[at(ROW.OY, r)]
        f[at(ROW.TOZ, t)] = f[at(ROW.OZ, r)]
        f[at(ROW.TU1, t)] = f[at(ROW.U1, r)]
        f[at(ROW.TU2, t)] = f[at(ROW.U2, r)]
        f[at(ROW.T_LOBE, t)] = f[at(ROW.CHOSEN, r)]
    for t in range(c):
        offset = par(stride, first, idx[lst + _U(t)])
        x, y, z, ok = lobe_sample(
            sampler,
            f[at(ROW.T_LOBE, t)],
            p,
            offset,
            f[at(ROW.TOX, t)],
            f[at(ROW.TOY, t)],
            f[at(ROW.TOZ, t)],
            f[at(ROW.TU1, t)],
            f[at(ROW.TU2, t)],
            vndf,
        )
        f[at(ROW.TX, t)] = x
        f[at(ROW.TY, t)] = y
        f[at(ROW.TZ, t)] = z
        f[at(ROW.TOK, t)] = 1.0 if ok else 0.0
    for t in range(c):
        r = idx[lst + _U(t)]
        f[at(ROW.IX, r)] = f[at(ROW.TX, t)]
        f[at(ROW.IY, r)] = f[at(ROW.TY, t)]
        f[at(ROW.IZ, r)] = f[at(ROW.TZ, t)]
        f[at(ROW.OK, r)] = f[at(ROW.TOK, t)]


@block
def lobe_outputs_pass(k, on, ms, p, stride, first, m, f, W, E, P):
    """Lobe slot k's weight w_k (RGB), albedo E_k (RGB, 0 below the horizon) and probability
    at every row, into the (n*8*3), (n*8*3), (n*8) outputs; zeros for an inactive slot."""
    for r in range(m):
        offset = par(stride, first, r)
        b = _U(first + r) * _U(N_LOBES) + _U(k)
        up = f[at(ROW.OZ, r)] > 0.0
        L = factor_of(k, f, r)
        w = offset + LOBE_PARAM.WEIGHT_COLOR + 3 * k
        for c in range(3):
            W[b * _U(3) + _U(c)] = L * p[w + c] if on else 0.0
            e = albedo_of(k, c, p, offset, f, r, ms)
            E[b * _U(3) + _U(c)] = e if (on and up) else 0.0
        P[b] = f[at(ROW.PROBABILITY + k, r)] if on else 0.0


@block
def albedo_lobe_pass(k, dmodel, ms, p, stride, first, m, f):
    """ROW.A0..A2 += w_k E_k of lobe slot k (dmodel: unused, see ``albedo_of``)."""
    for r in range(m):
        offset = par(stride, first, r)
        L = factor_of(k, f, r)
        w = offset + LOBE_PARAM.WEIGHT_COLOR + 3 * k
        f[at(ROW.A0, r)] += L * p[w] * albedo_of(k, opaque(0), p, offset, f, r, ms)
        f[at(ROW.A1, r)] += L * p[w + 1] * albedo_of(k, opaque(1), p, offset, f, r, ms)
        f[at(ROW.A2, r)] += L * p[w + 2] * albedo_of(k, opaque(2), p, offset, f, r, ms)


@block
def rgb_out_pass(first, m, f, out):
    """out[3 (first + r) + c] = A_c, 0 where wo is below the horizon."""
    for r in range(m):
        j = _U(3) * _U(first + r)
        up = f[at(ROW.OZ, r)] > 0.0
        out[j] = f[at(ROW.A0, r)] if up else 0.0
        out[j + _U(1)] = f[at(ROW.A1, r)] if up else 0.0
        out[j + _U(2)] = f[at(ROW.A2, r)] if up else 0.0


each_eval = lobe_loop("each_eval", eval_lobe_pass, literal=True)
each_pdf = lobe_loop("each_pdf", pdf_lobe_pass, literal=False)
each_albedo = lobe_loop("each_albedo", albedo_lobe_pass, literal=False)
