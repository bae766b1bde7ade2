"""Kernel compilation settings shared by every compiled formula of the package.

Used by the lobe models (``models``), the samplers (``sampling``), the microfacet lobes
(``microfacet``), the surface kernels (``nodes``) and the batch launcher (``_launch``):
it lives at the top of the package so that none of them reaches into another's private
module.  Each formula of the paper is written once, as a scalar function compiled by
numba (``kernel``: compiled for compiled callers only, without the CPython entry point
numba would build for each; a Python call uses a twin that has one); the batch drivers
(``models/_kernels.py``, ``sampling/_kernels.py``) loop over arrays and call them.  The
same functions are what the tests verify: there is no second NumPy copy.

``fastmath`` is restricted to flags that keep IEEE semantics for NaN/Inf (the input checks
and the ``max(eps, .)`` guards of Listing 1 rely on them) but allow contraction and
reciprocal approximations that do not change results beyond rounding.

Speed comes from LLVM vectorising the batch loops (AVX2/AVX-512: 4-8 rows at once).
That only happens when a loop body has no calls into libm: ``math.acos`` is one, so the
formulas use the ``acos`` below (a polynomial, accurate to ~1 ulp in float64).  PyPI's
llvmlite is built without Intel SVML, so numba has no vector ``acos`` of its own.
"""

import math
import types
from collections.abc import Callable, Sequence
from typing import Any

import numba
import numpy as np

FASTMATH = {"contract", "arcp", "nsz", "afn"}


def _kernel_dispatcher() -> type:
    from numba.core.registry import CPUDispatcher

    class Kernel(CPUDispatcher):  # type: ignore[misc, valid-type]
        """A numba dispatcher compiled for compiled callers only, without the CPython and C
        entry points that numba builds by default for every function (measured: 40 one-line
        functions and their caller compile in 2.0 s instead of 3.3 s).  A call from Python
        goes to a twin of the function compiled with them (``python_twin``), cached on disk
        under its own name (the compiled-only form is not cached, ``_compiled_only``), so
        that neither ever loads the other's machine code."""

        def __call__(self, *args: Any, **kws: Any) -> Any:
            return self.python_twin(*args, **kws)

        @property
        def python_twin(self) -> Any:
            twin = self.__dict__.get("_python_twin")
            if twin is None:
                f = self.py_func
                g = types.FunctionType(f.__code__, f.__globals__, f.__name__, f.__defaults__, f.__closure__)
                g.__qualname__ = f.__qualname__ + "__python"
                g.__module__, g.__doc__ = f.__module__, f.__doc__
                # with the CPython entry point (not the C one: nothing calls a twin through a
                # C function pointer), and with reference counting: from Python a formula may
                # be called with arrays (array expressions allocate their results)
                options = {k: v for k, v in self.targetoptions.items() if not k.startswith("no_c") and k != "_nrt"}
                twin = self.__dict__["_python_twin"] = numba.njit(cache=True, **options, **NO_CFUNC)(g)
            return twin

    return Kernel


_Kernel = _kernel_dispatcher()


def _compiled_only(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """A decorator compiling for compiled callers with these numba options, as a ``Kernel``
    dispatcher: no CPython or C entry points (the per-function part of numba's compile time
    that a function only called from compiled code never uses).

    Not cached on disk: a compiled caller links its callees' code into its own, so the
    cached drivers and runners that inline a kernel hold it already, and a process that
    loads them never compiles the kernel.  Caching each kernel as well cost a cold start
    a cache lookup and a write per specialisation (measured: 40 one-line functions and
    their caller compile in 1.55 s uncached, 1.98 s cached).  The Python twin is cached."""

    def decorate(f: Callable[..., Any]) -> Any:
        if numba.config.DISABLE_JIT:  # type: ignore[attr-defined]
            return f
        return _Kernel(
            py_func=f, locals={}, targetoptions=dict(options, no_cpython_wrapper=True, no_cfunc_wrapper=True)
        )

    return decorate


def elementwise(f: Any, *args: Any) -> Any:
    """``f(*args)`` for a scalar formula ``f`` (a ``kernel``) called from Python with arrays:
    the arguments broadcast together, passed to ``f`` as flat C-contiguous float64 arrays,
    and the result (an array, or a tuple of them) reshaped to the broadcast shape.

    Why: numba compiles a function once per distinct argument type, and an array's type
    holds its dimension count, layout and writability, so a formula called with arrays of
    a few shapes (a table's 2-D grid, a broadcast view) compiled once for each, a third of
    a second apiece; flattened, every call uses one specialisation.

    Example
    -------
    >>> import numpy as np
    >>> from openpbr_diffuse.models.eon import rho_ms
    >>> elementwise(rho_ms, np.full((2, 3), 0.5), 0.7).shape
    (2, 3)
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in args))
    shape = arrays[0].shape if arrays else ()
    flat = [np.array(a, dtype=np.float64, order="C").reshape(-1) for a in arrays]
    out = f(*flat)
    if isinstance(out, tuple):
        return tuple(np.asarray(o).reshape(shape) for o in out)
    return np.asarray(out).reshape(shape)


#: numba's reference counting (NRT) off: a function compiled with ``_nrt=False`` (a numba
#: target option) allocates no array, and numba emits none of the increments and decrements
#: of array references it otherwise emits for every array-valued variable.  ``block``, the
#: ``serial`` packing loop and the batch ``driver`` loops only read and write arrays their
#: caller owns (or stack buffers), so they need none, and lowering them is that much less
#: work: a cold ``eval`` of a material measured ~10 % less CPU (tools/bench.py --cold).  A
#: function that did allocate fails to compile under them instead of running.
NO_NRT: dict[str, Any] = {"_nrt": False}

#: Without numba's C entry point (``cfunc`` wrapper), which numba builds for every compiled
#: function and which only a caller through a raw C function pointer uses: the package's
#: compiled functions are called from Python (the CPython entry point) or from compiled
#: code (a direct call).  Each wrapper is a small function numba lowers and LLVM compiles.
NO_CFUNC: dict[str, Any] = {"no_cfunc_wrapper": True}

#: Without either entry point: for functions only compiled code calls (the overloads of
#: ``helper`` and ``unrolled``; ``kernel`` and ``block`` get the same from ``Kernel``).
NO_WRAPPERS: dict[str, Any] = {"no_cfunc_wrapper": True, "no_cpython_wrapper": True}

#: Decorator for scalar formula functions: compiled for the batch drivers that call them and
#: inlined there by LLVM (``forceinline``); callable from Python too (``Kernel``), where a
#: formula may also be given arrays (NumPy broadcasting; numba allocates the results).
kernel = _compiled_only(fastmath=FASTMATH, error_model="numpy", forceinline=True)

#: Decorator for the kernels over buffers (the surface's block passes and the functions
#: reading a material's parameter row, ``nodes._surface_*``): as ``kernel``, without NRT.
#: From Python (tests) they run as ``kernel`` does, through a twin with NRT.
block = _compiled_only(fastmath=FASTMATH, error_model="numpy", forceinline=True, **NO_NRT)

#: Decorator for the per-value input predicates (``_arrays``): as ``kernel``, strict IEEE
#: arithmetic (their NaN and Inf comparisons are the point).
predicate = _compiled_only(error_model="numpy", forceinline=True)

#: Decorator for a function inlined in numba's IR at its call sites, never compiled on its
#: own: one whose ``stack_buffer`` must live in its caller's frame (``_local_params`` of
#: ``nodes._surface_drivers``, a material's parameters copied for a block).  The tiny integer
#: helpers (scratch indices, block bounds) use ``helper`` instead.
inline = numba.njit(inline="always")


def _helper() -> Callable[[Callable[..., Any]], Any]:
    from numba.extending import register_jitable

    return register_jitable(error_model="numpy", forceinline=True, **NO_WRAPPERS)


#: Decorator for the tiny integer helpers called from every pass (scratch indices, block
#: bounds, lobe bits): typed without their arguments' literal values, so compiled once per
#: process for all call sites (numba's ``register_jitable``), and inlined by LLVM.  (Inlined
#: in numba's IR instead, as ``inline`` does, each of their hundreds of call sites cost a
#: copy of the helper's IR to type and lower.)
helper = _helper()

#: Decorator for the batch drivers of the models and the samplers (``models._kernels``,
#: ``sampling._kernels``) and the input checks' counting loops (``_arrays``), which
#: ``_launch.launch`` runs: serial loops that release the GIL, cached; numpy's error model
#: (x/0 gives inf, not an exception) so that rows below the horizon can be computed and then
#: discarded without a branch.
driver = numba.njit(nogil=True, cache=True, fastmath=FASTMATH, error_model="numpy", **NO_NRT, **NO_CFUNC)

#: Decorator for the block runners of the surface's verbs (``nodes._surface_drivers``):
#: cached, ``nogil`` (the launcher's pool runs them on several threads at once), serial,
#: without NRT (their scratch is a ``stack_buffer`` pointer; they allocate nothing).
runner = numba.njit(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy", **NO_NRT, **NO_CFUNC)

#: Decorator for a compiled loop that is neither a formula nor a runner (the packing of a
#: material's inputs, ``nodes._surface_kernels.pack_drive``): cached, strict IEEE arithmetic.
serial = numba.njit(cache=True, error_model="numpy", **NO_NRT, **NO_CFUNC)

#: Decorators for the random walks of the microsurface simulators (``simulation``): the
#: per-path loops (``walk``) and the steps they call (``walk_step``: compiled for compiled
#: callers only, as ``kernel``, and inlined by LLVM; inlined in numba's IR instead, each of
#: their call sites was a copy to type and lower, and the layered walk compiled three times
#: slower, same results bit for bit).  No fastmath: the walks rely on IEEE
#: comparisons free of inf and NaN at grazing angles, and their speed comes from the
#: per-path loop, not from vectorisation.  With NRT: a walk allocates its tallies.  numpy's
#: error model, as every other compiled loop of the package: a division is one instruction,
#: not a test for a zero divisor and a ZeroDivisionError path (the walks compile faster, same
#: results bit for bit; measurements in docs/benchmarks/bench.md, "Measurements moved from the
#: code").
walk = numba.njit(cache=True, nogil=True, error_model="numpy", **NO_CFUNC)
walk_step = _compiled_only(forceinline=True, error_model="numpy")

#: Decorator for a scalar formula's NumPy form (``microfacet.fresnel``): a ufunc, typed on
#: first call and cached.
ufunc = numba.vectorize(cache=True)

#: Decorator for a loop that allocates its result and sums into it with reassociation
#: allowed (every fastmath flag; the spherical-harmonic projection of
#: ``approximations.sh``).
reduction = numba.njit(cache=True, fastmath=True)

PI = math.pi
INV_PI = 1.0 / math.pi
EPS = 1e-7  # the epsilon of Listing 1 (f_ms guards)

#: Floor of the max(mu_i, mu_o) denominators (QON Eq. 1, FON Eq. 10, tan(beta) of full
#: Oren-Nayar).  Directions as close to the horizon as a subnormal mu are valid input, but
#: s / max(mu) overflows there (f = inf, or 0 * inf = NaN at zero roughness).  Below 1e-7
#: f * mu_i is negligible, so the floor only keeps the result finite in float32 and float64.
MU_FLOOR = 1e-7
HALF_PI = 0.5 * math.pi


@kernel
def max_mu(mu_i: float, mu_o: float) -> float:
    """max(mu_i, mu_o), floored at ``MU_FLOOR``: the denominator of QON's and FON's s/t."""
    return max(max(mu_i, mu_o), MU_FLOOR)


#: asin(y) = y + y^3 P(y^2) for 0 <= y <= 1/2: P is the degree-11 polynomial interpolating
#: the Maclaurin series of (asin(sqrt z) - sqrt z) / z^(3/2) (evaluated in exact rational
#: arithmetic, 89 terms) at the 12 Chebyshev nodes of [0, 1/4].  Interpolation error of P
#: < 1.4e-15 relative, i.e. < 6e-17 relative in asin; ``tests/test_kernels.py`` checks
#: ``acos`` against ``math.acos`` (<= 2 ulp over [-1, 1]).
_ASIN_P = (
    0.1666666666666665,
    0.07500000000020764,
    0.044642857103423646,
    0.03038194736709848,
    0.02237204763174451,
    0.017355259955786323,
    0.013929652902326633,
    0.011875494382636922,
    0.007802949477353317,
    0.016035514349148825,
    -0.01074905033969781,
    0.028169218060881414,
)
_P0, _P1, _P2, _P3, _P4, _P5, _P6, _P7, _P8, _P9, _P10, _P11 = _ASIN_P


@kernel
def _asin_small(y):
    """asin(y) for 0 <= y <= 1/2 (no libm call: vectorisable).

    P(z) by Estrin's scheme (pairs, then powers z^2, z^4, z^8): the longest chain of
    dependent multiply-adds is 5 instead of Horner's 12, which matters where a row's
    arithmetic is one long chain (the surface's drivers)."""
    z = y * y
    z2 = z * z
    z4 = z2 * z2
    z8 = z4 * z4
    r0 = (_P0 + _P1 * z) + (_P2 + _P3 * z) * z2
    r1 = (_P4 + _P5 * z) + (_P6 + _P7 * z) * z2
    r2 = (_P8 + _P9 * z) + (_P10 + _P11 * z) * z2
    p = (r0 + r1 * z4) + r2 * z8
    return y + y * z * p


@kernel
def acos(x: float) -> float:
    """arccos(x) for x in [-1, 1], in float64, to ~1 ulp; a drop-in for ``math.acos``.

    |x| <= 1/2: pi/2 - asin(x); |x| > 1/2: 2 asin(sqrt((1 - |x|)/2)) (1 - |x| is exact
    there), mirrored to pi - . for x < 0.  Both branches are computed and one selected, so
    the loop that inlines it stays branch-free.  Arguments outside [-1, 1] give NaN.
    """
    a = abs(1.0 * x)
    near = HALF_PI - _asin_small(min(a, 0.5))
    far = 2.0 * _asin_small(math.sqrt(max(0.5 * (1.0 - a), 0.0)))
    t = near if a <= 0.5 else far
    t = t if a <= 1.0 else math.nan
    return t if x >= 0.0 else PI - t


def stack_buffer(size: int, dtype: Any = numba.float64) -> Any:
    """A compiled function returning a buffer of ``size`` elements (uninitialised) in the
    stack frame of the compiled function that calls it, as ``np.empty(size)`` would on the
    heap: a typed pointer, indexed as an array is (``buf[i]``; no bounds, no negative
    indices, no length).

    What it is for: LLVM knows that such a buffer aliases no other pointer, so a loop that
    stores into it can keep the loads of its other arrays out of the loop (hoisted, when their
    addresses do not change) and vectorise; with a heap buffer it must assume that the stores
    may change them.  The surface's block drivers keep their scratch and their copy of one
    material's parameters in such buffers (``nodes._surface_drivers``).  ``size`` is a
    constant: the frame is sized when the function is compiled (keep it to some kilobytes).

    A pointer rather than an array (``numba.carray`` of it): numba lowers each index of an
    array through a proxy of the array's whole structure, hundreds of times in the
    surface's passes, and a pointer index as one address computation (measured: a cold
    ``eval`` of a material ~1 s less CPU); the runners then need no reference counting."""
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def _alloca(typingctx):
        def codegen(context, builder, signature, args):
            return cgutils.alloca_once(builder, context.get_value_type(dtype), size=size)

        return numba.types.CPointer(dtype)(), codegen

    return _alloca


def _pointer_intrinsic():
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def pointer_of(typingctx, a):
        """The data pointer of a C-contiguous 1-D array ``a`` (compiled code only): indexed
        as ``a`` is (no bounds, no negative indices), and lowered as cheaply as a
        ``stack_buffer``.  For a function that
        indexes its array arguments many times (the packing of a material's parameters);
        the array must outlive every use of the pointer (an argument of the caller does)."""
        if not (isinstance(a, numba.types.Array) and a.ndim == 1 and a.layout == "C"):
            return None

        def codegen(context, builder, signature, args):
            return cgutils.create_struct_proxy(signature.args[0])(context, builder, value=args[0]).data

        return numba.types.CPointer(a.dtype)(a), codegen

    return pointer_of


pointer_of = _pointer_intrinsic()


def _opaque_intrinsic():
    from numba.extending import intrinsic

    @intrinsic
    def opaque(typingctx, x):
        """x, typed without its literal value (``types.unliteral``).

        numba compiles a function once per distinct literal argument of its call sites: the
        surface's block passes, called once per lobe slot with the slot a constant, were
        compiled eight to ten times each (and every kernel they call with it).  Passing
        ``opaque(k)`` compiles them once; LLVM still folds the constant once the pass is
        inlined into its driver, so the code is the same."""

        def codegen(context, builder, signature, args):
            return args[0]

        return numba.types.unliteral(x)(x), codegen

    return opaque


opaque = _opaque_intrinsic()


def unrolled(
    name: str, argnames: Sequence[str], body_of: Callable[[int], str], env: dict[str, Any], module: str
) -> Callable[..., Any]:
    """A function ``name(*argnames)`` for compiled code whose body is generated, while its
    caller is typed, from the value of its first argument, a compile-time constant (a
    literal int): ``body_of(value)`` returns the body's Python source (over ``argnames``
    and the names of ``env``), which numba inlines into the caller.  The one place the
    package writes code from code: the surface's lobe dispatch (``by_constant``) and its
    loops over a set of lobes (``nodes._surface_passes.lobe_loop``) unroll into straight
    calls with constant ids, so that each call compiles its own lobe's formula only.  (A
    run-time ``if k == ...`` chain is typed branch by branch: every call site compiled every
    lobe.)  Returns the Python stub, which raises if called from Python."""
    from numba import errors, types
    from numba.extending import overload

    args = ", ".join(argnames)
    names: dict[str, Any] = {"__name__": module}
    exec(f"def {name}({args}):\n    raise NotImplementedError('compiled only')\n", names)
    stub = names[name]

    def implementation(*argtypes):
        if not isinstance(argtypes[0], types.IntegerLiteral):
            raise errors.TypingError(f"{name}: the first argument must be a compile-time constant")
        body = body_of(argtypes[0].literal_value).replace("\n", "\n    ")
        ns = dict(env, __name__=module)
        exec(f"def impl({args}):\n    {body}\n", ns)
        return ns["impl"]

    typer = eval(f"lambda {args}: implementation({args})", {"implementation": implementation, "__name__": module})
    overload(stub, inline="always", prefer_literal=True, jit_options=NO_WRAPPERS)(typer)  # type: ignore[arg-type]
    return stub


def by_constant(name: str, argnames: Sequence[str], table: Sequence[Any], module: str) -> Callable[..., Any]:
    """``name(k, *rest)`` in compiled code calls ``table[k](*rest)``, k a compile-time constant
    (``unrolled``): the dispatch of a family of functions with one signature."""
    rest = ", ".join(argnames[1:])
    env = {f"f{k}": fn for k, fn in enumerate(table)}
    return unrolled(name, argnames, lambda k: f"return f{k}({rest})", env, module)
