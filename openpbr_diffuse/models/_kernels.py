"""Batch drivers: one serial ``nogil`` loop per verb, specialised per model and channel count.

Every formula is the scalar function of its model module, inlined here (``lobe_terms``,
``albedo_terms``).  A driver is compiled for one model id and one channel count C (1, 3,
or any), both compile-time constants: the model branches fold away and the loop body is
straight-line code over flat C-contiguous buffers with constant row strides, which LLVM
vectorises (4-8 rows per instruction).  With a run-time model id, run-time C or
run-time strides it does not, and the loop runs 4-10x slower.

Rows are independent: ``_launch.launch`` runs a large call's loop over runs of rows on the
package's thread pool (no ``prange``: one compiled body per driver).

Arithmetic is in the inputs' dtype: float64 input runs the formulas of the model modules,
float32 input their float32 twins (``_float32.float32_twin``: the same source with float32
constants), so that a float32 call computes in float32 throughout and LLVM packs twice as
many rows per vector instruction.  The unit-length checks stay in float64 for both (the
same directions are accepted whatever the dtype).  The float32 results are within the
bound stated in ``api.evaluate`` of the float64 ones (``tests/test_float32.py``).

The value checks of ``_arrays`` (unit directions, parameter ranges, finiteness) run inside
the same loop, through the same predicates (``is_unit``, ``is_within``): the inputs are
read once instead of once more per argument.  A driver returns 1 when some row
failed (0 otherwise); the public verbs then run the full checks, which raise with their
usual message.

Inputs whose rows are all the same (a scalar roughness, one rho for every row, a fixed
direction) are tiled into a buffer of at most ``CHUNK`` rows and the driver is called
chunk by chunk, so no input is ever expanded to the full batch.  Drivers are built on
first use (``functools.cache``) and compiled lazily per dtype; numba caches them on disk.
"""

import functools
import math

import numpy as np
from numba import errors, types
from numba.extending import overload

from .._arrays import is_unit, is_within
from .._float32 import float32_twin
from .._jit import driver, kernel, pointer_of
from .._launch import _U, launch, rows
from .eon import eon_albedo_terms, eon_average_terms, eon_terms, rho_ms
from .fon import fon_albedo, fon_terms
from .fujii import fujii_albedo_terms, fujii_terms
from .full_on import full_on_terms
from .gotanda import gotanda_albedo, gotanda_terms
from .lambert import lambert_albedo, lambert_terms
from .qon import qon_AB, qon_albedo, qon_average_albedo, qon_terms
from .registry import INFO, MIX_RHO2, MIX_RHO_MS
from .van_ouwerkerk import van_ouwerkerk_terms

LAMBERT, QON, QON_FOOTNOTE, QON_VO, QON_FUJII, FON, FULL_ON, GOTANDA, EON, EON_APPROX = (
    INFO[n].id
    for n in (
        "lambert",
        "qon",
        "qon_footnote",
        "qon_van_ouwerkerk",
        "qon_fujii",
        "fon",
        "full_on",
        "gotanda",
        "eon",
        "eon_approx",
    )
)


def _is_float32(t):
    """True for numba's float32 type: the driver's rows are float32 (use the twins)."""
    return isinstance(t, types.Float) and t.bitwidth == 32


def _of(t, formula):
    """``formula``, or its float32 twin when ``t`` (a numba type) is float32."""
    return float32_twin(formula) if _is_float32(t) else formula


def _consts(t, *values):
    """``values`` as constants of the driver's float type ``t`` (float64: the Python floats)."""
    return tuple(np.float32(v) for v in values) if _is_float32(t) else values


def _model_id(model):
    """The model id of a driver's call site: a compile-time constant (the driver closes over it)."""
    if not isinstance(model, types.IntegerLiteral):
        raise errors.TypingError("the model id of a batch driver must be a compile-time constant")
    return model.literal_value


def lobe_terms(model, ix, iy, iz, ox, oy, oz, r):
    """(g, h, <E_F>) of f = rho g + m(rho) h at one pair of directions (both above the horizon).

    Compiled form only (``_lobe_terms``): the model id selects one model's formula while the
    driver is typed, so a driver compiles its own model's kernels and no other's (numba types
    every branch of a run-time ``if model == ...``, and so compiled all ten models' kernels
    into each driver)."""
    raise NotImplementedError("compiled only: called from the batch drivers")


@overload(lobe_terms, inline="always")
def _lobe_terms(model, ix, iy, iz, ox, oy, oz, r):
    """s = wi.wo - mu_i mu_o = sin(theta_i) sin(theta_o) cos(phi) lies in [-1, 1] for unit
    vectors, and is clamped to it here, the one place every model gets s from.  Directions
    are accepted within |w| = 1 +- UNIT_TOL (``_arrays``), and for such not-quite-unit
    vectors s reaches -(1 + 2 UNIT_TOL) at grazing opposite azimuth, where FON's
    1 + r s/t (t = 1 for s <= 0, Eq. 10) and with it FON, EON and "eon_approx" went
    negative (-5e-6 in float64 at r = 1).  The clamp keeps every model's f >= 0 without
    renormalising the inputs (a square root and a division per direction, and results
    changed by rounding everywhere); it only moves rows whose |w| differs from 1.
    Full Oren-Nayar keeps its published negative values (``full_on``).
    """
    m = _model_id(model)
    lo, hi, zero = _consts(r, -1.0, 1.0, 0.0)
    eon_terms_, fon_terms_, qon_AB_, qon_terms_ = (_of(r, f) for f in (eon_terms, fon_terms, qon_AB, qon_terms))
    vo_terms_, fujii_terms_, full_on_terms_ = (_of(r, f) for f in (van_ouwerkerk_terms, fujii_terms, full_on_terms))
    gotanda_terms_, lambert_terms_ = _of(r, gotanda_terms), _of(r, lambert_terms)
    if m == EON or m == EON_APPROX:
        approx = m == EON_APPROX

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            return eon_terms_(iz, oz, min(max(ix * ox + iy * oy, lo), hi), r, approx)
    elif m == FON:

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            return fon_terms_(iz, oz, min(max(ix * ox + iy * oy, lo), hi), r), zero, zero
    elif m == QON or m == QON_FOOTNOTE:
        (a_const,) = _consts(r, 0.33 if m == QON else 0.57)

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            A, B = qon_AB_(r, a_const)
            return qon_terms_(iz, oz, min(max(ix * ox + iy * oy, lo), hi), A, B), zero, zero
    elif m == QON_VO:

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            return vo_terms_(ix, iy, iz, ox, oy, oz, r), zero, zero
    elif m == QON_FUJII:

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            g, h = fujii_terms_(iz, oz, min(max(ix * ox + iy * oy, lo), hi), r)
            return g, h, zero
    elif m == FULL_ON:

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            g, h = full_on_terms_(iz, oz, min(max(ix * ox + iy * oy, lo), hi), r)
            return g, h, zero
    elif m == GOTANDA:

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            return gotanda_terms_(iz, oz, min(max(ix * ox + iy * oy, lo), hi), r), zero, zero
    else:

        def impl(model, ix, iy, iz, ox, oy, oz, r):
            return lambert_terms_(), zero, zero

    return impl


def albedo_terms(model, mu, r, average):
    """(e_g, e_h, <E_F>) of E = rho e_g + m(rho) e_h; the average <E> when ``average`` (0 or 1).

    Compiled form only (``_albedo_terms``, one model's formula per driver, as ``lobe_terms``)."""
    raise NotImplementedError("compiled only: called from the batch drivers")


@overload(albedo_terms, inline="always")
def _albedo_terms(model, mu, r, average):
    """Each model module holds its own closed form: QON family Eq. 8-9 (``qon``), FON
    Eq. 12-15 and the lobes of FON's shape (``fon``, ``gotanda``, ``fujii``), EON Eq. 20
    (``eon``).  ("full_on" has none: its albedo comes from the reference tables.)
    """
    m = _model_id(model)
    avg_on = bool(_model_id(average))  # 0/1, a compile-time constant as the model id
    (zero,) = _consts(r, 0.0)
    eon_average_terms_, eon_albedo_terms_ = _of(r, eon_average_terms), _of(r, eon_albedo_terms)
    qon_AB_, qon_average_albedo_, qon_albedo_ = (_of(r, f) for f in (qon_AB, qon_average_albedo, qon_albedo))
    fon_albedo_, gotanda_albedo_ = _of(r, fon_albedo), _of(r, gotanda_albedo)
    fujii_albedo_terms_, lambert_albedo_ = _of(r, fujii_albedo_terms), _of(r, lambert_albedo)
    if m == EON or m == EON_APPROX:
        approx = m == EON_APPROX
        if avg_on:

            def impl(model, mu, r, average):
                return eon_average_terms_(r, approx)
        else:

            def impl(model, mu, r, average):
                return eon_albedo_terms_(mu, r, approx)
    elif m == QON or m == QON_FOOTNOTE or m == QON_VO:
        (a_const,) = _consts(r, 0.57 if m == QON_FOOTNOTE else 0.33)
        if avg_on:

            def impl(model, mu, r, average):
                A, B = qon_AB_(r, a_const)
                return qon_average_albedo_(A, B), zero, zero
        else:

            def impl(model, mu, r, average):
                A, B = qon_AB_(r, a_const)
                return qon_albedo_(mu, A, B), zero, zero
    elif m == FON:

        def impl(model, mu, r, average):
            return fon_albedo_(mu, r, avg_on), zero, zero
    elif m == GOTANDA:

        def impl(model, mu, r, average):
            return gotanda_albedo_(mu, r, avg_on), zero, zero
    elif m == QON_FUJII:

        def impl(model, mu, r, average):
            g, h = fujii_albedo_terms_(mu, r, avg_on)
            return g, h, zero
    else:

        def impl(model, mu, r, average):
            return lambert_albedo_(), zero, zero

    return impl


@kernel
def mix(kind, rho, g, h, avg):
    """rho g + m(rho) h for the model's rho dependence ``kind`` (registry MIX_*)."""
    if kind == MIX_RHO_MS:
        return rho * g + rho_ms(rho, avg) * h
    if kind == MIX_RHO2:
        return rho * g + rho * rho * h
    return rho * g


@kernel
def shade(kind, tint, up, p, g, h, avg):
    """One channel: ``rho g + m(rho) h`` (reference) or ``rho f(rho = 1)`` (white_tint); 0 unless ``up``.

    Written with selects, not branches, so that the batch loop stays vectorisable.
    """
    q = 1.0 if tint else p
    v = mix(kind, q, g, h, avg)
    v = p * v if tint else v
    return v if up else 0.0


_MIX = {info.id: info.mix for info in INFO.values()}


def _channels(C):
    """The compile-time channel count of a driver: 1, 3, or 0 for "read it from the arrays"."""
    return C if C in (1, 3) else 0


@kernel
def checked_rho(rho, c, ok):
    """rho[c] (in the input dtype), and ``ok`` and-ed with its range check ([0, 1], finite)."""
    p = rho[c]
    return p, ok & is_within(p, 0.0, 1.0, False, False)


@kernel
def write_row(nc, kind, tint, up, rho, out, i, m, g, h, avg, ok):
    """Shade row i into ``out`` for every channel; returns ``ok`` and-ed with the rho checks.

    ``nc`` is the driver's compile-time channel variant (3, 1, or 0 = any count, ``m``
    channels a row), so after inlining only one branch is left and the RGB and grey loops
    are straight-line code.  ``rho`` and ``out`` are arrays or their data pointers.
    """
    if nc == 3:
        c = _U(i) * _U(3)
        p, ok = checked_rho(rho, c, ok)
        out[c] = shade(kind, tint, up, p, g, h, avg)
        p, ok = checked_rho(rho, c + _U(1), ok)
        out[c + _U(1)] = shade(kind, tint, up, p, g, h, avg)
        p, ok = checked_rho(rho, c + _U(2), ok)
        out[c + _U(2)] = shade(kind, tint, up, p, g, h, avg)
    elif nc == 1:
        p, ok = checked_rho(rho, _U(i), ok)
        out[i] = shade(kind, tint, up, p, g, h, avg)
    else:
        c = _U(i) * _U(m)
        for k in range(m):
            p, ok = checked_rho(rho, c + _U(k), ok)
            out[c + _U(k)] = shade(kind, tint, up, p, g, h, avg)
    return ok


def write_row_of(nc, kind, tint, up, rho, out, i, m, g, h, avg, ok):
    """``write_row``, or its float32 twin when the row's terms are float32 (compiled only)."""
    raise NotImplementedError("compiled only: called from the batch drivers")


@overload(write_row_of, inline="always")
def _write_row_of(nc, kind, tint, up, rho, out, i, m, g, h, avg, ok):
    write = _of(g, write_row)

    def impl(nc, kind, tint, up, rho, out, i, m, g, h, avg, ok):
        return write(nc, kind, tint, up, rho, out, i, m, g, h, avg, ok)

    return impl


def eval_driver(model, C):
    """The ``evaluate`` loop for one model id and channel count C (one driver for every C
    other than 1 and 3: see ``_channels``)."""
    return _eval_driver(model, _channels(C))


def albedo_driver(model, C):
    """The ``directional_albedo`` / ``average_albedo`` loop for one model id and channel
    count C (one driver for every C other than 1 and 3: the 81 and 85 samples of two
    spectral grids share it)."""
    return _albedo_driver(model, _channels(C))


@functools.cache
def _eval_driver(model, nc):
    """The ``evaluate`` loop for one model id and channel variant ``nc`` (``_channels``).

    ``drive(tint, rlo, rhi, wi, wo, r, rho, out) -> bad``: wi, wo flat (N*3,), r (N,),
    rho (N*C,), out (N*C,); ``bad`` is 1 when some row's inputs fail the ``_arrays``
    checks (unit directions, roughness in [rlo, rhi], rho in [0, 1], all finite), which
    are fused into the loop rather than run as separate passes over the inputs, else 0.

    The failures are or-ed into a flag, not counted: LLVM sizes the vectors of a loop by
    the widest type its loads, stores and reductions carry, and a 64-bit count limited the
    float32 loop to 4 rows per 256-bit instruction (8 with the flag: float32 ``evaluate``
    ~2x faster; the float64 loop has 4 either way).
    """
    kind = _MIX[model]

    @driver
    def drive(tint, rlo, rhi, wi_rows, wo_rows, r_rows, rho_rows, out_rows):
        n = r_rows.shape[0]
        m = rho_rows.shape[0] // max(n, 1)
        # indexed through their data pointers (``_jit.pointer_of``: cheaper to compile)
        wi, wo, r = pointer_of(wi_rows), pointer_of(wo_rows), pointer_of(r_rows)
        rho, out = pointer_of(rho_rows), pointer_of(out_rows)
        failed = False
        for i in range(n):
            j = _U(i) * _U(3)
            # in the input dtype from here on (float32 rows: the float32 twins); the range
            # checks compare in it (rlo, rhi arrive rounded to it), is_unit in float64
            ix, iy, iz = wi[j], wi[j + _U(1)], wi[j + _U(2)]
            ox, oy, oz = wo[j], wo[j + _U(1)], wo[j + _U(2)]
            ri = r[i]
            ok = is_unit(ix, iy, iz) & is_unit(ox, oy, oz) & is_within(ri, rlo, rhi, False, False)
            g, h, avg = lobe_terms(model, ix, iy, iz, ox, oy, oz, ri)
            up = (iz > 0.0) & (oz > 0.0)  # f = 0 when either direction is below the horizon
            ok = write_row_of(nc, kind, tint, up, rho, out, i, m, g, h, avg, ok)
            failed |= not ok
        return 1 if failed else 0

    return drive


@functools.cache
def _albedo_driver(model, nc):
    """The ``directional_albedo`` and ``average_albedo`` loops of one model and channel variant.

    ``drive(tint, average, rlo, rhi, mu, r, rho, out) -> bad`` with the input checks fused
    as in ``eval_driver`` (mu in [0, 1]; ``bad`` a flag, as there).  E(mu) at mu = 0 is the
    limit mu -> 0; with ``average`` (a run-time flag: one compiled function holds both
    loops, each typed with its own closed form) mu is neither read nor checked.
    """
    kind = _MIX[model]

    @driver
    def drive(tint, average, rlo, rhi, mu_rows, r_rows, rho_rows, out_rows):
        n = r_rows.shape[0]
        m = rho_rows.shape[0] // max(n, 1)
        mu, r = pointer_of(mu_rows), pointer_of(r_rows)  # as in ``eval_driver``
        rho, out = pointer_of(rho_rows), pointer_of(out_rows)
        failed = False
        if average:
            for i in range(n):
                ri = r[i]
                ok = is_within(ri, rlo, rhi, False, False)
                eg, eh, avg = albedo_terms(model, ri, ri, 1)  # mu is not read
                ok = write_row_of(nc, kind, tint, True, rho, out, i, m, eg, eh, avg, ok)
                failed |= not ok
            return 1 if failed else 0
        for i in range(n):
            ri = r[i]
            m_i = mu[i]
            ok = is_within(ri, rlo, rhi, False, False) & is_within(m_i, 0.0, 1.0, False, False)
            eg, eh, avg = albedo_terms(model, m_i, ri, 0)
            ok = write_row_of(nc, kind, tint, True, rho, out, i, m, eg, eh, avg, ok)
            failed |= not ok
        return 1 if failed else 0

    return drive


def evaluate_rows(model, tint, rlo, rhi, wi, wo, r, rho, lead, C, dtype):
    """f for arrays broadcasting to ``lead`` (types and shapes checked, values not yet).

    Returns the flat (prod(lead)*C,) output and the number of runs of rows (driver calls)
    in which some row's values fail the ``_arrays`` checks (roughness in [rlo, rhi]); when
    that is not 0 the output is garbage and the caller must raise (by running the full
    checks).
    """
    n = math.prod(lead)
    out = np.empty(n * C, dtype=dtype)
    wi, twi = rows(wi, lead, 3)
    wo, two = rows(wo, lead, 3)
    r, tr = rows(r, lead)
    rho, trho = rows(rho, lead, C)
    t = np.dtype(dtype).type
    bad = launch(
        eval_driver(model, C),
        (tint, t(rlo), t(rhi)),
        [(wi, 3, twi), (wo, 3, two), (r, 1, tr), (rho, C, trho)],
        [(out, C)],
        n,
    )
    return out, bad


def albedo_rows(model, tint, average, rlo, rhi, mu, r, rho, lead, C, dtype):
    """E(mu) (or <E>) for arrays broadcasting to ``lead``; (flat output, failed rows) as ``evaluate_rows``."""
    n = math.prod(lead)
    out = np.empty(n * C, dtype=dtype)
    r, tr = rows(r, lead)
    mu, tmu = (r, tr) if average else rows(mu, lead)  # average: mu is not read
    rho, trho = rows(rho, lead, C)
    t = np.dtype(dtype).type
    bad = launch(
        albedo_driver(model, C),
        (tint, bool(average), t(rlo), t(rhi)),
        [(mu, 1, tmu), (r, 1, tr), (rho, C, trho)],
        [(out, C)],
        n,
    )
    return out, bad
