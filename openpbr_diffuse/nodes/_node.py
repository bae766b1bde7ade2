"""What every shading node shares: its interface read from a MaterialX nodedef.

A node class names its nodedef (``NODEDEF``); its Python signature, input names, types,
defaults and ranges are built from the nodedef's inputs (``materialx_defs``), so the node
cannot drift from the MaterialX library.  Inputs with a ``defaultgeomprop`` (normals,
tangents supplied by the renderer) default to None and are keyword-only.
"""

import inspect
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .. import _arrays as ar
from .materialx_defs import InputDef, nodedef_inputs


class NodeMeta(type):
    """Gives node classes a ``__signature__`` computed (lazily) from their nodedef."""

    @property
    def __signature__(cls) -> inspect.Signature:
        return cls.signature()  # type: ignore[attr-defined]  # each node class defines it


def _geomprop(idef):
    return bool(idef.defaultgeomprop) and idef.default is None


def node_signature(
    nodedef: str, options: Sequence[tuple[str, object]] = (), keyword_only: bool = False
) -> inspect.Signature:
    """inspect.Signature of a node: the nodedef inputs (library order, geomprops last and
    keyword-only) followed by keyword-only ``options`` ((name, default) pairs)."""
    defs = nodedef_inputs(nodedef)
    kind = inspect.Parameter.KEYWORD_ONLY if keyword_only else inspect.Parameter.POSITIONAL_OR_KEYWORD
    params = [inspect.Parameter(n, kind, default=d.default) for n, d in defs.items() if not _geomprop(d)]
    params += [
        inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=None) for n, d in defs.items() if _geomprop(d)
    ]
    params += [inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=v) for n, v in options]
    return inspect.Signature(params)


def _range(name, arr, lo, hi, n):
    lo = (lo,) * n if lo is not None and not isinstance(lo, tuple) else lo
    hi = (hi,) * n if hi is not None and not isinstance(hi, tuple) else hi
    for k in range(n):
        comp = arr[..., k] if n > 1 else arr
        what = f" (component {k})" if n > 1 else ""
        a, b = (lo[k] if lo is not None else -np.inf), (hi[k] if hi is not None else np.inf)
        ar.in_range(name, comp, np.float64, a, b, f"{what}, the range of the MaterialX nodedef")


def convert_input(idef: InputDef, value: Any) -> Any:
    """Validate and convert one input value against its nodedef entry.

    float -> float64 array (...); colorN/vectorN -> (..., N) (a scalar is repeated; a
    vector3 with a defaultgeomprop is a unit direction, e.g. a normal); boolean -> bool.
    Values outside the nodedef's [uimin, uimax] raise ValueError naming the input.
    """
    name, t = idef.name, idef.type
    if value is None:
        if _geomprop(idef):
            return None
        raise TypeError(f"{name} must not be None")
    if t == "boolean":
        if not isinstance(value, (bool, np.bool_)):
            raise TypeError(f"{name} must be a boolean (MaterialX type boolean), got {type(value).__name__}")
        return bool(value)
    if t == "float":
        a = ar.as_float(name, value, np.float64)
        _range(name, a, idef.uimin, idef.uimax, 1)
        return a
    if t.startswith(("color", "vector")):
        n = int(t[-1])
        if _geomprop(idef):
            return ar.directions(name, value, np.float64)
        a = ar.as_float(name, value, np.float64)
        if a.ndim == 0:
            a = np.repeat(a, n)
        if a.shape[-1] != n:
            raise ValueError(f"{name} must have shape (..., {n}) (MaterialX type {t}), got shape {a.shape}")
        _range(name, a, idef.uimin, idef.uimax, n)
        return a
    if t == "integer":
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise TypeError(f"{name} must be an integer, got {type(value).__name__}")
        return int(value)
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string (MaterialX type {t}), got {type(value).__name__}")
    return value


def is_default(idef: InputDef, value: object) -> bool:
    """True if a converted value equals the nodedef default everywhere (geomprops: not given)."""
    if _geomprop(idef):
        return value is None
    if isinstance(value, np.ndarray):
        return bool(np.all(value == np.asarray(idef.default, dtype=np.float64)))
    return value == idef.default


def bind_inputs(cls: Any, args: Sequence[object], kwargs: Mapping[str, object]) -> dict[str, Any]:
    """Bind a node constructor call to its signature; unknown names -> ValueError naming them."""
    sig = cls.signature()
    unknown = sorted(set(kwargs) - set(sig.parameters))
    if unknown:
        raise ValueError(
            f"{cls.__name__}: unknown input(s) {', '.join(unknown)}; "
            f"the inputs of {cls.NODEDEF} are {', '.join(nodedef_inputs(cls.NODEDEF))}"
        )
    try:
        bound = sig.bind(*args, **kwargs)
    except TypeError as exc:
        raise TypeError(f"{cls.__name__}: {exc}") from None
    bound.apply_defaults()
    return dict(bound.arguments)
