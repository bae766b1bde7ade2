"""The batch drivers of ``OpenPBRSurface``: one per verb (lobes, albedo, eval, pdf, sample),
and the calls that run them over the rows of a request.

A driver splits its rows into blocks of ``B`` and runs the block passes of
``_surface_passes`` on each: the state of mu_o, then one pass per active lobe with the lobe
id a constant, so that every pass is a vectorised loop (the lobe-at-a-time order of a
wavefront renderer).  ``sample`` chooses the lobe of each row, gathers the rows of each lobe
(``compact``) and runs that lobe's sampler on them only, then evaluates the mixture pdf at
the sampled directions with the same passes as ``pdf``: the pdf returned with a sample is
``pdf(wo, wi)`` of the returned wi to within 4 ulp on every x86-64 CPU (the same source
compiled into two drivers; numba compiles for the host, and a row that falls in a loop's
vector body in one call and in its remainder in another may round differently where LLVM
contracts multiply-adds: 1 ulp seen with AMD Zen 4 code, none with Sandy Bridge or Sapphire
Rapids code).  What is bit for bit by construction: a call's rows do not depend on the
thread count nor on how a call is split at multiples of ``B`` rows (the same compiled runner
runs the same blocks).

Each driver is built per parameter stride (0: one material for every row; N_PARAMS: a
material per row), lobe set and diffuse model (the ``lobes`` driver: stride and lobe set),
compile-time constants, on first use, with
``nogil``: a call of fewer than
``SERIAL_ROWS`` rows runs it on the calling thread, a larger one runs it over runs of blocks
on the package's thread pool (``_Builds``).
No input is checked here: the public class checks its inputs once, at construction and on
each call's directions.
"""

import functools
import math
import os
import zlib

import numba
import numpy as np

from .._jit import block, helper, inline, opaque, runner, stack_buffer
from .._launch import _U, SERIAL_ROWS, executor, launch, rows
from . import lobes as _lobes
from ._surface_kernels import (
    COAT,
    DIFFUSE,
    FUZZ,
    METAL,
    N_LOBES,
    N_PARAMS,
    SPECULAR,
)
from ._surface_kernels import LOBES as LOBE_MODULES
from ._surface_params import D_EON, N_CCURVE, N_CURVE, N_SAMPLERS
from ._surface_passes import (
    NROWS,
    ROW,
    B,
    at,
    choose_pass,
    clear_rgb_pass,
    compact,
    each_albedo,
    each_eval,
    each_pdf,
    fill_pass,
    ggx_pass,
    ggx_pdf_pass,
    is_on,
    load_pass,
    load_u_pass,
    lobe_outputs_pass,
    probability_pass,
    rgb_out_pass,
    sample_pass,
    span,
    state_passes,
)


def _registry_key():
    """An int of the lobe registry: its lobes' names and the source of the engine's modules
    (the lobe modules, ``_surface_params``, ``_surface_kernels``, ``_surface_passes``).  Every
    runner closes over it, and numba's cache indexes a closure's compilations by its values:
    a process with another registry (a lobe added) or an edited lobe compiles its own
    runners instead of loading ones compiled for other lobes."""
    here = os.path.dirname(os.path.abspath(__file__))
    files = {m.__file__ for m in LOBE_MODULES} | {
        os.path.join(os.path.dirname(_lobes.__file__), f) for f in ("_common.py", "_samplers.py", "__init__.py")
    }
    files |= {os.path.join(here, f) for f in ("_surface_params.py", "_surface_kernels.py", "_surface_passes.py")}
    key = zlib.crc32(" ".join(m.NAME for m in LOBE_MODULES).encode())
    for path in sorted(files):
        with open(path, "rb") as fh:
            key = zlib.crc32(fh.read(), key)
    return key


#: the registry's key (``_registry_key``), a closure value of every runner
REGISTRY_KEY = _registry_key()


# --------------------------------------------------------------------------- buffers
# Each run of blocks keeps its scratch, its compaction lists and (one material) a copy of the
# material's parameters in stack buffers: loads of the parameters then leave the passes'
# loops, which vectorise (``_jit.stack_buffer``).
_scratch = stack_buffer(NROWS * B)
_lists = stack_buffer(N_SAMPLERS * B, numba.int64)
_counts = stack_buffer(N_SAMPLERS, numba.int64)
_param_buffer = stack_buffer(N_PARAMS)


@inline
def _local_params(p):
    """One material's parameters, copied to a stack buffer."""
    params = _param_buffer()
    for i in range(N_PARAMS):
        params[i] = p[i]
    return params


def _each_sampler_source():
    """The body of ``_each_sampler``, generated from the samplers' table: ``sample_pass`` of
    every sampler that some row of the block uses, the sampler id a constant once inlined
    (vndf too, for the samplers that branch on it: ``sample_reflection``)."""
    lines = ["def _each_sampler(vndf, p, stride, first, f, idx, cnt):"]
    for s, vndf_branches in enumerate(_lobes.BRANCHES_ON_VNDF):
        call = "sample_pass(opaque({}), opaque({}), p, stride, first, f, idx, cnt)"
        lines.append(f"    if cnt[{s}]:")
        if vndf_branches:
            lines += ["        if vndf:", "            " + call.format(s, True), "        else:"]
            lines.append("            " + call.format(s, False))
        else:
            lines.append("        " + call.format(s, "vndf"))
    return "\n".join(lines) + "\n"


def _generated(source, name, env):
    namespace = dict(env, __name__=__name__)
    exec(compile(source, __file__, "exec"), namespace)
    return namespace[name]


_each_sampler = block(
    _generated(_each_sampler_source(), "_each_sampler", {"sample_pass": sample_pass, "opaque": opaque})
)


@block
def _choose(ud, u, first, m, span_rows, f):
    if ud == 3:
        load_u_pass(3, u, first, m, f)
        choose_pass(3, span_rows, f)
    else:
        load_u_pass(2, u, first, m, f)
        choose_pass(2, span_rows, f)


# --------------------------------------------------------------------------- block runs
# ``run(t, nt, ...)`` processes the t-th of nt runs of blocks: the rows' blocks
# [t nb / nt, (t + 1) nb / nt).  It is compiled once per verb and parameter stride and
# called by both builds of the driver (``_Builds``), so that the serial and the parallel
# driver share one compiled body.  Every verb's runner is the one frame of ``_RUN`` around
# the verb's step (``_runner_factory``).


@helper
def _block_range(t, nt, n):
    nb = (n + B - 1) // B
    return t * nb // nt, (t + 1) * nb // nt


@helper
def _block(b, n):
    """Block b of n rows: its first row first, its rows m and the rows its passes run over."""
    first = b * B
    m = min(B, n - first)
    return first, m, span(m)


#: The frame of every verb's runner: the registry's key in the closure, the scratch (and the
#: sampler lists, for a step that reads them), one material's parameters copied to the stack,
#: then per block of the run wo (and wi, ``load_wi``), the state of mu_o (``state_passes``;
#: with the diffuse terms and the GGX basis albedos unless ``albedos`` is False) and the
#: verb's ``step``.
_RUN = """
def {factory}(stride, lobes{model}):
    registry = REGISTRY_KEY

    def {name}(t, nt, {args}):
        _ = registry  # the cache's index holds it (``REGISTRY_KEY``)
        n = wo.shape[0] // 3
        f = _scratch(){buffers}
        if stride == 0:  # one material: a local copy (stride is a constant: the other branch is pruned)
            params = _local_params(p)
        else:  # a material per row: read where they are
            params = p
        b0, b1 = _block_range(t, nt, n)
        for b in range(b0, b1):
            first, m, span_rows = _block(b, n)
            load_pass(wo, first, m, f, ROW.OX){load_wi}
            state_passes(
                opaque(lobes), active, opaque(dmodel), ms, opaque({albedos}), opaque({albedos}),
                params, stride, first, span_rows, f,
            )
            step({step_args})

    return runner({name})
"""

#: the frame's names a step may read besides the runner's arguments (``_RUN``)
_FRAME = ("lobes", "dmodel", "stride", "n", "f", "idx", "cnt", "params", "first", "m", "span_rows")


def _runner_factory(verb, args, step, albedos=True, load_wi=False):
    """The factory ``_<verb>_run(stride, lobes[, dmodel])`` of a verb's block runner
    ``<verb>_run(t, nt, *args)`` (``_Builds``): the frame ``_RUN`` around ``step``, an
    ``inline`` function whose parameters are named after what it reads (the frame's names,
    ``_FRAME``, or the runner's ``args``).  The diffuse model is a constant of the factory
    unless ``args`` names it (the ``lobes`` runner); the runner's closure holds plain ints
    only, so that numba's cache finds it in a new process.  With ``load_wi`` the frame loads
    the argument wi too, with wo (streaming both before the parameters are read is faster with
    a material per row)."""
    names = [a.strip() for a in args.split(",")]
    code = step.py_func.__code__
    reads = code.co_varnames[: code.co_argcount]
    unknown = [a for a in reads if a not in _FRAME and a not in names]
    if unknown:
        raise NameError(f"{step.py_func.__name__} reads {', '.join(unknown)}: neither the frame's nor an argument")
    source = _RUN.format(
        factory=f"_{verb}_run",
        name=f"{verb}_run",
        model="" if "dmodel" in names else ", dmodel",
        args=args,
        buffers="\n        idx = _lists()\n        cnt = _counts()" if "idx" in reads else "",
        albedos=albedos,
        step_args=", ".join(reads),
        load_wi="\n            load_pass(wi, first, m, f, ROW.IX)" if load_wi else "",
    )
    env = dict(
        REGISTRY_KEY=REGISTRY_KEY,
        ROW=ROW,
        _scratch=_scratch,
        _lists=_lists,
        _counts=_counts,
        _local_params=_local_params,
        _block_range=_block_range,
        _block=_block,
        load_pass=load_pass,
        state_passes=state_passes,
        opaque=opaque,
        runner=runner,
        step=step,
    )
    return _generated(source, f"_{verb}_run", env)


@inline
def _bsdf(lobes, on, dmodel, weighted, ms, params, stride, first, m, span_rows, f, out):
    """out (rows of the block) = sum_k w_k f_k over the lobes ``on`` (``weighted``), or their
    unweighted f_k; wi in the scratch."""
    ggx_pass(on, params, stride, first, span_rows, f)
    clear_rgb_pass(f, span_rows)
    if dmodel == D_EON:  # the EON lobe's pass typed with the model a literal, where it is an argument too
        each_eval(lobes, on, D_EON, weighted, ms, params, stride, first, span_rows, f)
    else:
        each_eval(lobes, on, dmodel, weighted, ms, params, stride, first, span_rows, f)
    rgb_out_pass(first, m, f, out)


@inline
def _mixture_pdf(lobes, active, dmodel, track, vndf, params, stride, first, span_rows, f):
    """ROW.MIXTURE_PDF = sum_k P_k pdf_k(wi | wo) (and, when ``track``, ROW.CHOSEN_PDF: the
    chosen lobe's own pdf); wi and the probabilities in the scratch."""
    ggx_pdf_pass(active, vndf, params, stride, first, span_rows, f)
    fill_pass(f, ROW.MIXTURE_PDF, span_rows, 0.0)
    if track:
        fill_pass(f, ROW.CHOSEN_PDF, span_rows, 0.0)
    each_pdf(lobes, active, dmodel, track, vndf, params, stride, first, span_rows, f)


@inline
def _albedo_step(lobes, active, dmodel, ms, params, stride, first, m, span_rows, f, out):
    """out (n*3) = sum_k w_k E_k."""
    clear_rgb_pass(f, span_rows)
    each_albedo(lobes, active, dmodel, ms, params, stride, first, span_rows, f)
    rgb_out_pass(first, m, f, out)


@inline
def _eval_step(lobes, active, only, dmodel, ms, params, stride, first, m, span_rows, f, out):
    """out (n*3) = sum_k w_k f_k, or the unweighted f_only when only >= 0 (wi loaded by the frame)."""
    on = active if only < 0 else active & (1 << only)
    _bsdf(lobes, on, dmodel, only < 0, ms, params, stride, first, m, span_rows, f, out)


@inline
def _lobes_step(lobes, active, dmodel, sel, ms, with_f, params, stride, first, m, span_rows, f, wi, W, E, P, out):
    """W, E (n*8*3), P (n*8): weight, albedo and probability of every lobe slot at wo; with
    ``with_f`` also out (n*3) = sum_k w_k f_k(wi, wo) as ``eval`` gives it: a material's lobes
    and its BSDF from one pass over the rows (the state of mu_o is computed once for both),
    and one runner compiled for both uses.

    The diffuse model is a run-time argument here (one runner per lobe set serves every
    model: a process that reads materials of several models compiles it once); the EON
    diffuse lobe's BSDF pass is typed with the model a constant (``_bsdf``), so that its loop
    vectorises as in ``eval``."""
    probability_pass(lobes, active, sel, params, stride, first, span_rows, f, ms)
    for k in range(N_LOBES):  # & lobes: a constant, so LLVM drops the slots outside the set
        lobe_outputs_pass(k, is_on(active & lobes, k), ms, params, stride, first, m, f, W, E, P)
    if with_f:
        load_pass(wi, first, m, f, ROW.IX)
        _bsdf(lobes, active, dmodel, True, ms, params, stride, first, m, span_rows, f, out)


@inline
def _pdf_step(lobes, active, dmodel, sel, ms, vndf, params, stride, first, m, span_rows, f, out):
    """out (n) = sum_k P_k pdf_k(wi | wo); 0 where wo is below the horizon (wi loaded by the frame)."""
    probability_pass(lobes, active, sel, params, stride, first, span_rows, f, ms)
    _mixture_pdf(lobes, active, dmodel, False, vndf, params, stride, first, span_rows, f)
    for r in range(m):
        out[_U(first + r)] = f[at(ROW.MIXTURE_PDF, r)] if f[at(ROW.OZ, r)] > 0.0 else 0.0


@inline
def _sample_step(lobes, active, dmodel, sel, ms, vndf, params, stride, n, first, m, span_rows, f, idx, cnt, u, wi, out):
    """Pick lobe k with P_k (u[0]), sample it (u[1:3], or u[0] rescaled and u[1] when u has
    2 columns); wi (n*3), out (n) = the mixture pdf at wi; 0 marks a failed sample."""
    probability_pass(lobes, active, sel, params, stride, first, span_rows, f, ms)
    _choose(u.shape[0] // n, u, first, m, span_rows, f)
    compact(opaque(dmodel), span_rows, f, idx, cnt)
    _each_sampler(vndf, params, stride, first, f, idx, cnt)
    _mixture_pdf(lobes, active, dmodel, True, vndf, params, stride, first, span_rows, f)
    for r in range(m):
        j = _U(3) * _U(first + r)
        up = f[at(ROW.OZ, r)] > 0.0
        good = up & (f[at(ROW.OK, r)] > 0.0) & (f[at(ROW.CHOSEN_PDF, r)] > 0.0)
        out[_U(first + r)] = f[at(ROW.MIXTURE_PDF, r)] if good else 0.0
        wi[j] = f[at(ROW.IX, r)] if up else 0.0
        wi[j + _U(1)] = f[at(ROW.IX + 1, r)] if up else 0.0
        wi[j + _U(2)] = f[at(ROW.IX + 2, r)] if up else 1.0


_albedo_run = _runner_factory("albedo", "active, ms, p, wo, out", _albedo_step)
_eval_run = _runner_factory("eval", "active, only, ms, p, wi, wo, out", _eval_step, albedos=False, load_wi=True)
_lobes_run = _runner_factory("lobes", "active, dmodel, sel, ms, with_f, p, wi, wo, W, E, P, out", _lobes_step)
_pdf_run = _runner_factory("pdf", "active, sel, ms, vndf, p, wo, wi, out", _pdf_step, load_wi=True)
_sample_run = _runner_factory("sample", "active, sel, ms, vndf, p, wo, u, wi, out", _sample_step)


# --------------------------------------------------------------------------- threads

#: A parallel call splits its blocks into this many runs per thread (the pool's threads take
#: them as they become free, which evens out a machine whose cores run at different speeds).
RUNS_PER_THREAD = 2


#: The lobe sets a runner is compiled for, smallest first: a call runs the runner of the first
#: set that holds every lobe its material(s) can have (``_Builds.runner``), so that a verb
#: compiles the lobe passes of the base surface's three lobes for the base surface, and every
#: lobe's only for a material that needs them.
BASE = (1 << DIFFUSE) | (1 << SPECULAR) | (1 << METAL)
LAYERED = BASE | (1 << COAT) | (1 << FUZZ)
ALL = (1 << N_LOBES) - 1
LOBE_SETS = (BASE, LAYERED, ALL)


def lobe_set(active):
    """The first of ``LOBE_SETS`` that holds the lobes of ``active``."""
    return next(s for s in LOBE_SETS if active & ~s == 0)


class _Builds:
    """A verb's block runners and how a call runs them.

    A runner is built per parameter stride (0: one material; N_PARAMS: a material per row),
    lobe set (``LOBE_SETS``) and diffuse model, all three constants it closes over (plain
    ints: a closure over them is found in numba's cache), on first use; with
    ``model_at_run_time`` (the ``lobes`` verb) per stride and lobe set only, the diffuse
    model being an argument of the runner.  ``one`` and
    ``each`` are the base surface's runners with the EON diffuse lobe.

    The runners are compiled with ``nogil``, and a large call runs them on the package's
    thread pool: one compiled body serves the serial and the parallel call.  (A numba
    ``prange`` driver would be a second compilation of the whole body, which numba
    re-optimises as it inlines it -- a minute of a cold start -- and its OpenMP threads,
    once idle, took up to milliseconds to wake on the test VM.)"""

    def __init__(self, factory, model_at_run_time=False):
        self.factory = factory
        self.model_at_run_time = model_at_run_time
        self.runners = {}
        self.one, self.each = self.runner(False, BASE, D_EON), self.runner(True, BASE, D_EON)

    def runner(self, per_row, active, dmodel):
        """The runner of a call's lobes ``active`` (bit mask) and diffuse model."""
        if self.model_at_run_time:
            key = (per_row, lobe_set(active))
        else:
            key = (per_row, lobe_set(active), dmodel)
        run = self.runners.get(key)
        if run is None:
            run = self.runners[key] = self.factory(N_PARAMS if per_row else 0, *key[1:])
        return run

    def __call__(self, run, n, *args):
        threads = numba.get_num_threads()
        if n < SERIAL_ROWS or threads == 1:
            run(0, 1, *args)
            return
        nt = min((n + B - 1) // B, RUNS_PER_THREAD * threads)
        pool = executor(threads)
        jobs = [pool.submit(run, t, nt, *args) for t in range(nt)]
        for job in jobs:
            job.result()


LOBES = _Builds(_lobes_run, model_at_run_time=True)
ALBEDO = _Builds(_albedo_run)
EVAL = _Builds(_eval_run)
PDF = _Builds(_pdf_run)
SAMPLE = _Builds(_sample_run)
BUILDS = {"lobes": LOBES, "albedo": ALBEDO, "eval": EVAL, "pdf": PDF, "sample": SAMPLE}


@functools.cache
def tables():
    """(C, R): the padded GGX albedo tables (``microfacet.tables.padded_tables``), read by
    ``pack_drive`` only: it collapses them per material into the PARAM.CURVE_* and PARAM.E* curves
    in mu that the per-row drivers interpolate."""
    from ..microfacet.tables import padded_tables

    C, R = padded_tables()
    if R.shape[2] != N_CURVE or C.shape[1] != N_CCURVE:  # the parameter layout reserves them
        raise RuntimeError(
            f"GGX albedo tables have {R.shape[2] - 2} and {C.shape[1] - 2} mu nodes; the "
            f"parameter layout expects {N_CURVE - 2} (N_CURVE) and {N_CCURVE - 2} (N_CCURVE)"
        )
    return C, R


def _run(builds, flags, head, params, lead, dirs, outs):
    """Run a verb's driver over the rows of ``lead``: ``params`` is one material (never copied
    or tiled) or materials broadcasting to ``lead`` (expanded to a material per row)."""
    n = math.prod(lead)
    if n == 0:
        return
    run = builds.runner(params.ndim > 1, flags.active, flags.dmodel)
    if params.ndim == 1 and n == 1:  # one material, one row (lobes(wo) of a material): no batch machinery
        run(0, 1, *head, params, *(rows(d, lead, k)[0] for d, k in dirs), *(o for o, _ in outs))
        return
    if params.ndim == 1:
        inputs = []
        for d, k in dirs:
            b, t = rows(d, lead, k)
            inputs.append((b, k, t))
        first = len(head) + 1  # the first direction buffer (3 a row) follows the parameters

        def drive(*args):
            builds(run, args[first].size // 3, *args)

        launch(drive, head + (params,), inputs, outs, n, split=False)  # the runners use the pool themselves
        return
    # a material per row (no copy when the materials already have the rows' shape).  The
    # passes of a short block run up to 3 rows past its end (``span``) and read a material for
    # each: the whole blocks run on the rows as they are, the last, partial block on a copy
    # padded with its last material (the padding rows' results are not stored)
    p = np.ascontiguousarray(np.broadcast_to(params, lead + (N_PARAMS,))).reshape(-1)
    full = [np.ascontiguousarray(np.broadcast_to(d, lead + (k,))).reshape(-1) for d, k in dirs]
    whole = n - n % B
    if whole:
        builds(
            run,
            whole,
            *head,
            p[: whole * N_PARAMS],
            *(d[: whole * k] for d, (_, k) in zip(full, dirs)),
            *(o[: whole * k] for o, k in outs),
        )
    if whole < n:
        tail = np.empty(B * N_PARAMS)
        tail[: (n - whole) * N_PARAMS] = p[whole * N_PARAMS :]
        tail[(n - whole) * N_PARAMS :] = np.tile(p[(n - 1) * N_PARAMS :], B - (n - whole))
        builds(
            run,
            n - whole,
            *head,
            tail,
            *(d[whole * k :] for d, (_, k) in zip(full, dirs)),
            *(o[whole * k :] for o, k in outs),
        )


def lobes_rows(flags, params, wo, lead, wi=None):
    """(W (..., 8, 3), E (..., 8, 3), P (..., 8)) for float64 arrays broadcasting to ``lead``,
    and with ``wi`` the BSDF f (..., 3) at (wi, wo) as a fourth array (one pass for both)."""
    n = math.prod(lead)
    W = np.empty(n * N_LOBES * 3)
    E = np.empty(n * N_LOBES * 3)
    P = np.empty(n * N_LOBES)
    out = np.empty(n * 3)
    with_f = wi is not None
    _run(
        LOBES,
        flags,
        (flags.active, flags.dmodel, flags.sel, flags.ms, with_f),
        params,
        lead,
        [(wi if with_f else wo, 3), (wo, 3)],  # without wi the runner does not read it
        [(W, N_LOBES * 3), (E, N_LOBES * 3), (P, N_LOBES), (out, 3)],
    )
    lobes = W.reshape(lead + (N_LOBES, 3)), E.reshape(lead + (N_LOBES, 3)), P.reshape(lead + (N_LOBES,))
    return (*lobes, out.reshape(lead + (3,))) if with_f else lobes


def albedo_rows(flags, params, wo, lead):
    out = np.empty(math.prod(lead) * 3)
    _run(ALBEDO, flags, (flags.active, flags.ms), params, lead, [(wo, 3)], [(out, 3)])
    return out.reshape(lead + (3,))


def eval_rows(flags, params, wi, wo, lead, only=-1):
    out = np.empty(math.prod(lead) * 3)
    _run(EVAL, flags, (flags.active, only, flags.ms), params, lead, [(wi, 3), (wo, 3)], [(out, 3)])
    return out.reshape(lead + (3,))


def pdf_rows(flags, params, wo, wi, lead):
    out = np.empty(math.prod(lead))
    _run(PDF, flags, (flags.active, flags.sel, flags.ms, flags.vndf), params, lead, [(wo, 3), (wi, 3)], [(out, 1)])
    return out.reshape(lead)


def sample_rows(flags, params, wo, u, lead):
    n = math.prod(lead)
    wi = np.empty(n * 3)
    out = np.empty(n)
    _run(
        SAMPLE,
        flags,
        (flags.active, flags.sel, flags.ms, flags.vndf),
        params,
        lead,
        [(wo, 3), (u, u.shape[-1])],
        [(wi, 3), (out, 1)],
    )
    return wi.reshape(lead + (3,)), out.reshape(lead)
