"""The lobes of ``OpenPBRSurface``, one module each, and the registry the compiled engine is
assembled from (the shape of pbrt-v4's ``BxDF`` types: a lobe's verbs live together).

A lobe module declares, for the lobe at a surface row (parameters ``p`` from ``offset``,
layout ``_surface_params.PARAM``):

- ``NAME`` and ``LAYER`` (the layer it lies under: its weight's factor of mu_o);
- ``READS_DIFFUSE_MODEL`` (optional, False): its formulas depend on ``diffuse_model``, so its
  eval pass is compiled once per model (the diffuse lobe);
- ``weight_color(p, offset, c)``: K[c], the material part of its weight w[c] = L(mu_o) K[c];
- ``is_on(p, offset)``: whether the lobe can be non-zero (the material's active lobes);
- ``eval(p, offset, d, x)``: its own BSDF (RGB, weight not applied), ``d`` a ``Directions``
  and ``x`` an ``EvalInputs`` record;
- ``pdf(p, offset, d, dmodel, vndf, ggx_pdf)``: the solid-angle pdf of its sampler;
- ``sampler(dmodel)`` and ``sample_setup(p, offset)``: its sampler (``_samplers``) and that
  sampler's (width, side of the surface);
- ``albedo(c, p, offset, ms, st)``: its directional albedo in channel c from the row's
  ``LayerState``;
- ``constant_albedo(p, offset, c)`` and ``score(mx, p, offset, weight_at, constant, ms, st)``:
  its selection score |K E| (by max when ``mx``, else the RGB length), ``constant`` being
  |K e| (or max_c |K[c] e[c]|) of the constant colour e = ``constant_albedo``.

The verbs that several lobes declare alike are made from the lobe's constants by the
helpers of ``_common`` (``fixed_sampler``, ``sampler_width``, ``on_where_positive``,
``separable_albedo``, ``base_ggx_pdf``).

A lobe may also declare ``INPUTS``, names of unmodelled nodedef inputs it reads as they
are: they join the packed row, and the engine sets the module's ``INPUT`` (a namedtuple of
their offsets) when it is assembled, so the lobe reads ``p[offset + INPUT.<name>]``.

``REGISTRY`` lists the modules in slot order: the lobe id of a module is its row.  Adding a
lobe is its module and one row (``register``), before ``nodes._surface_kernels`` is imported:
the parameter layout, the dispatch of every verb (``dispatch``) and the lobe passes are
built from the registry when the engine is imported.

Example
-------
>>> [m.NAME for m in REGISTRY][:3]
['diffuse', 'specular', 'metal']
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from types import ModuleType
from typing import Any

from . import coat, diffuse, fuzz, metal, specular, subsurface, subsurface_transmission, transmission
from ._samplers import BRANCHES_ON_VNDF, SAMPLERS

__all__ = ["BRANCHES_ON_VNDF", "DECLARES", "REGISTRY", "SAMPLERS", "dispatch", "register"]

#: The lobe modules, in slot order (a lobe's id is its row).
REGISTRY: list[ModuleType] = [diffuse, specular, metal, transmission, subsurface, subsurface_transmission, coat, fuzz]

#: What a lobe module declares (``register`` checks them).
DECLARES = (
    "NAME",
    "LAYER",
    "weight_color",
    "is_on",
    "eval",
    "pdf",
    "sampler",
    "sample_setup",
    "albedo",
    "constant_albedo",
    "score",
)


def register(module: ModuleType) -> int:
    """Append a lobe module to ``REGISTRY`` (before the engine is imported); its lobe id.

    Raises
    ------
    TypeError
        ``module`` lacks one of ``DECLARES`` (named in the message).

    Example
    -------
    >>> import types
    >>> register(types.SimpleNamespace(NAME="none"))
    Traceback (most recent call last):
    ...
    TypeError: module: lobe 'none' does not declare LAYER, weight_color, is_on, eval, pdf, sampler, sample_setup, albedo, constant_albedo, score
    """
    missing = [n for n in DECLARES if not hasattr(module, n)]
    if missing:
        raise TypeError(f"module: lobe {getattr(module, 'NAME', module)!r} does not declare {', '.join(missing)}")
    REGISTRY.append(module)
    return len(REGISTRY) - 1


def dispatch(
    name: str, argnames: Sequence[str], table: Sequence[Callable[..., Any]], module: str, select: bool = False
) -> Callable[..., Any]:
    """A compiled function ``name(k, *rest)`` returning ``table[k](*rest)``, its body generated
    from the table: an if-chain on k (a run-time value, or a constant LLVM folds once the
    function is inlined), or with ``select`` every entry computed and one selected (cheap
    entries in a loop that should stay branch-free).

    Example
    -------
    >>> from openpbr_diffuse._jit import block
    >>> f = dispatch("pick", ("k", "x"), [block(lambda x: x), block(lambda x: 2.0 * x)], __name__)
    >>> f(1, 3.0)
    6.0
    """
    from ..._jit import block

    rest = ", ".join(argnames[1:])
    last = len(table) - 1
    lines = [f"def {name}({', '.join(argnames)}):"]
    if select:
        lines.append(f"    out = f{last}({rest})")
        lines += [f"    out = f{k}({rest}) if k == {k} else out" for k in range(last - 1, -1, -1)]
        lines.append("    return out")
    else:
        for k in range(last):
            lines += [f"    if k == {k}:", f"        return f{k}({rest})"]
        lines.append(f"    return f{last}({rest})")
    namespace: dict[str, Any] = {f"f{k}": f for k, f in enumerate(table)}
    namespace["__name__"] = module
    exec(compile("\n".join(lines) + "\n", __file__, "exec"), namespace)
    f = namespace[name]
    f.__doc__ = f"``{name}(k, {rest})``: entry k of its table (generated by ``lobes.dispatch``)."
    return block(f)
