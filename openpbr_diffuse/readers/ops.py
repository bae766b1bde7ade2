"""Values of the MaterialX stdlib nodes the readers evaluate on the CPU, at one point.

A table, not an if-chain: node category -> function(inputs, out_type) -> value, where
``inputs`` holds the node's resolved input values by name (floats, or float64 arrays for
colorN/vectorN) and ``out_type`` is the node's output type.  The semantics are those of
MaterialX's own GLSL implementations (``libraries/stdlib/genglsl``: inline ``sourcecode`` and
the ``mx_*.glsl`` functions), component-wise on numpy arrays: e.g. ``modulo`` is GLSL's
``mod`` (x - y floor(x / y)), ``ramptb`` mixes ``valueb`` to ``valuet`` by the clamped v,
``splitlr`` steps at ``center`` (its anti-aliasing width is 0 at one point), ``hsvtorgb``
is ``mx_hsvtorgb`` (Foley & van Dam, as OSL).

The evaluator prefers a node's library implementation graph when the data library has one
(``convert``, ``switch``, ``smoothstep`` on vectors, ``contrast``, ``range``, ``place2d``, ...),
so MaterialX's own graph defines those; this table covers the natively implemented nodes.
Nodes in neither (noise, cellnoise, worleynoise, geometry other than texcoord, matrices,
closures) are reported as unsupported by the readers, naming the node.  A value that is not
finite (ln of 0, sqrt of -1: undefined in GLSL) is kept, as GLSL keeps it (an unselected
branch may compute it); a shader input that ends up not finite fails its material.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

SCALAR_TYPES = ("float", "integer", "boolean", "string", "filename")


def _as(v, out_type):
    """Broadcast a value to ``out_type`` (float -> colorN/vectorN, extra components dropped,
    missing ones: alpha 1 for colours, 0 for vectors)."""
    if out_type in SCALAR_TYPES:
        if isinstance(v, np.ndarray):
            v = v.reshape(-1)[0]
        if out_type == "float" and isinstance(v, (bool, int, np.integer, np.bool_, np.floating)):
            return float(v)
        if out_type == "integer" and isinstance(v, (float, np.floating, np.integer, np.bool_)):
            return int(v)
        if out_type == "boolean" and isinstance(v, (np.bool_, np.integer, int)):
            return bool(v)
        return v
    n = int(out_type[-1])
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.size == 1:
        return np.repeat(a, n)
    if a.size >= n:
        return a[:n].copy()
    # color3 -> color4 (alpha 1), vector2 -> vector3 (0)
    return np.concatenate([a, np.ones(n - a.size) if out_type.startswith("color") else np.zeros(n - a.size)])


def _num(v):
    if isinstance(v, (tuple, list, np.ndarray)):
        return np.asarray(v, dtype=np.float64)
    if isinstance(v, str):
        raise TypeError(f"a string value {v!r} where a number is needed")
    return np.float64(v)  # numpy scalars: 1 / 0 is inf, as in GLSL, not ZeroDivisionError


def _vec(v):
    return np.asarray(_num(v), dtype=np.float64).reshape(-1)


def _divide(a, b):
    a, b = _num(a), _num(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(np.asarray(b) != 0.0, np.asarray(a) / np.where(np.asarray(b) != 0.0, b, 1.0), 0.0)
    return q


def _if(cmp):
    return lambda i, t: _as(
        i["in1"] if cmp(float(_as(i["value1"], "float")), float(_as(i["value2"], "float"))) else i["in2"], t
    )


def _if_bool(cmp):
    """ifgreater / ifequal / ifgreatereq with a boolean output (no in1 / in2: true / false)."""

    def f(i, t):
        if "in1" in i:
            return _if(cmp)(i, t)
        return bool(cmp(float(_as(i["value1"], "float")), float(_as(i["value2"], "float"))))

    return f


def _rotate2d(i, t):
    """MaterialX ``rotate2d``: (c x + s y, -s x + c y) with amount in degrees (its GLSL
    implementation ``mx_rotate_vector2``; a positive amount turns the vector clockwise)."""
    x, y = _vec(i["in"])[:2]
    a = np.radians(float(i["amount"]))
    c, s = np.cos(a), np.sin(a)
    return _as(np.array([c * x + s * y, -s * x + c * y]), t)


def _rotate3d(i, t):
    """MaterialX ``rotate3d`` (``mx_rotate_vector3``): Rodrigues' rotation of ``in`` by ``amount``
    degrees about the normalised ``axis``, written for v' = v M as MaterialX writes it:
    in cos + cross(in, axis) sin + axis dot(axis, in) (1 - cos)."""
    axis = _vec(i["axis"])[:3]
    norm = np.linalg.norm(axis)
    if norm == 0.0:
        raise ValueError("rotate3d: the axis is the zero vector")
    axis = axis / norm
    v = _vec(i["in"])[:3]
    a = np.radians(float(i["amount"]))
    s, c = np.sin(a), np.cos(a)
    return _as(v * c + np.cross(v, axis) * s + axis * np.dot(axis, v) * (1.0 - c), t)


def _switch(i, t):
    """MaterialX ``switch``: ``which`` 0 selects in1, 1 in2, ... (floored), as its library graph:
    a ``which`` at or beyond the number of inputs gives 0."""
    names = sorted((n for n in i if n.startswith("in") and n[2:].isdigit()), key=lambda n: int(n[2:]))
    k = int(np.floor(float(i["which"])))
    if k < 0:
        k = 0
    if k >= len(names):
        return _as(0.0, t)
    return _as(i[names[k]], t)


def _mod(a, b):
    """GLSL ``mod``: a - b floor(a / b) (MaterialX's ``mx_mod``); b = 0 gives 0."""
    a, b = _num(a), _num(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        bb = np.where(np.asarray(b) != 0.0, b, 1.0)
        return np.where(np.asarray(b) != 0.0, a - bb * np.floor(a / bb), 0.0)


def _round(v):
    """Round half away from zero (GLSL ``round`` leaves halves to the implementation; OSL's and
    C's ``round`` go away from zero)."""
    v = _num(v)
    return np.sign(v) * np.floor(np.abs(v) + 0.5)


def _smoothstep(i, t):
    """``mx_smoothstep_float``: 1 at or above high, 0 at or below low, else the Hermite step."""
    x, lo, hi = (np.broadcast_to(_num(i[k]), np.shape(_num(i["in"]))) for k in ("in", "low", "high"))
    x, lo, hi = (np.asarray(a, dtype=np.float64) for a in (x, lo, hi))
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.clip((x - lo) / np.where(hi != lo, hi - lo, 1.0), 0.0, 1.0)
    s = u * u * (3.0 - 2.0 * u)
    return _as(np.where(x >= hi, 1.0, np.where(x <= lo, 0.0, s)), t)


def _mixer(fn):
    """A compositing operator of MaterialX's genglsl: mix * fn(fg, bg) + (1 - mix) * bg."""

    def f(i, t):
        fg, bg, m = _num(i["fg"]), _num(i["bg"]), _num(i["mix"])
        return _as(m * fn(fg, bg) + (1.0 - m) * bg, t)

    return f


def _burn(fg, bg):
    """``mx_burn``: 0 where |fg| < eps, else 1 - (1 - bg) / fg (per component)."""
    fg, bg = np.broadcast_arrays(np.asarray(fg, dtype=np.float64), np.asarray(bg, dtype=np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(fg) < _EPS, 0.0, 1.0 - (1.0 - bg) / np.where(np.abs(fg) < _EPS, 1.0, fg))


def _dodge(fg, bg):
    """``mx_dodge``: 0 where |1 - fg| < eps, else bg / (1 - fg)."""
    fg, bg = np.broadcast_arrays(np.asarray(fg, dtype=np.float64), np.asarray(bg, dtype=np.float64))
    d = 1.0 - fg
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(d) < _EPS, 0.0, bg / np.where(np.abs(d) < _EPS, 1.0, d))


#: M_FLOAT_EPS of MaterialX's GLSL library (mx_math.glsl).
_EPS = 1e-8


def _burn_dodge(fn):
    """burn / dodge: MaterialX computes the mix inside (result = 0 where the operator is undefined)."""

    def f(i, t):
        fg, bg, m = _num(i["fg"]), _num(i["bg"]), _num(i["mix"])
        fgb, bgb = np.broadcast_arrays(np.asarray(fg, dtype=np.float64), np.asarray(bg, dtype=np.float64))
        undefined = np.abs(fgb) < _EPS if fn is _burn else np.abs(1.0 - fgb) < _EPS
        return _as(np.where(undefined, 0.0, m * fn(fgb, bgb) + (1.0 - m) * bgb), t)

    return f


def _hsvtorgb_3(hsv):
    """``mx_hsvtorgb`` (Foley & van Dam, as OSL's opcolor)."""
    h, s, v = (float(x) for x in hsv[:3])
    if s < 0.0001:
        return np.array([v, v, v])
    h = 6.0 * (h - np.floor(h))
    hi = int(np.trunc(h))
    f = h - hi
    p, q, tt = v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f))
    return np.array([(v, tt, p), (q, v, p), (p, v, tt), (p, q, v), (tt, p, v), (v, p, q)][min(hi, 5)])


def _rgbtohsv_3(rgb):
    """``mx_rgbtohsv`` (as OSL's opcolor): hue in [0, 1)."""
    r, g, b = (float(x) for x in rgb[:3])
    mincomp, maxcomp = min(r, g, b), max(r, g, b)
    delta = maxcomp - mincomp
    v = maxcomp
    s = delta / maxcomp if maxcomp > 0.0 else 0.0
    if s <= 0.0:
        h = 0.0
    else:
        if r >= maxcomp:
            h = (g - b) / delta
        elif g >= maxcomp:
            h = 2.0 + (b - r) / delta
        else:
            h = 4.0 + (r - g) / delta
        h /= 6.0
        if h < 0.0:
            h += 1.0
    return np.array([h, s, v])


def _colour_fn(fn):
    """A color3 -> color3 function applied to color3 / color4 (alpha kept)."""

    def f(i, t):
        a = _vec(i["in"])
        out = fn(a)
        return _as(np.concatenate([out, a[3:4]]) if t == "color4" else out, t)

    return f


def _luminance(i, t):
    """``mx_luminance``: the dot product with ``lumacoeffs`` in every colour channel (alpha kept)."""
    a = _vec(i["in"])
    lum = float(np.dot(a[:3], _vec(i["lumacoeffs"])[:3]))
    return _as(np.array([lum, lum, lum] + ([float(a[3])] if t == "color4" else [])), t)


def _unary(fn):
    return lambda i, t: _as(fn(_num(i["in"])), t)


def _normalize(i, t):
    a = _vec(i["in"])
    n = np.linalg.norm(a)
    return _as(a / n if n != 0.0 else np.full(a.shape, np.nan), t)  # GLSL: undefined (NaN)


def _ramp(axis, first, second):
    """ramplr / ramptb: mix(``first``, ``second``, clamp(texcoord[axis], 0, 1))."""

    def f(i, t):
        u = float(np.clip(_vec(i["texcoord"])[axis], 0.0, 1.0))
        return _as(_num(i[first]) * (1.0 - u) + _num(i[second]) * u, t)

    return f


def _split(axis, first, second):
    """splitlr / splittb: ``second`` where texcoord[axis] >= center, else ``first``
    (``mx_aastep`` with a zero filter width)."""

    def f(i, t):
        u = float(_vec(i["texcoord"])[axis])
        return _as(i[second] if u >= float(i["center"]) else i[first], t)

    return f


def _premult(i, t):
    a = _vec(i["in"])
    return _as(np.concatenate([a[:3] * a[3], a[3:4]]), t)


def _unpremult(i, t):
    a = _vec(i["in"])
    return _as(np.concatenate([a[:3] / a[3], a[3:4]]), t)  # alpha 0: not finite, as in GLSL


def _composite(alpha_fg, alpha_bg):
    """The Porter-Duff color4 operators of MaterialX's genglsl (over, in, out, mask):
    result = fg * alpha_fg(fg.a, bg.a) + bg * alpha_bg(fg.a, bg.a), then mixed with bg."""

    def f(i, t):
        fg, bg, m = _vec(i["fg"]), _vec(i["bg"]), float(i["mix"])
        out = fg * alpha_fg(fg[3], bg[3]) + bg * alpha_bg(fg[3], bg[3])
        return _as(m * out + (1.0 - m) * bg, t)

    return f


def _matte(i, t):
    """``matte`` (genglsl): (fg.rgb fg.a + bg.rgb (1 - fg.a), fg.a + bg.a (1 - fg.a)), mixed with bg."""
    fg, bg, m = _vec(i["fg"]), _vec(i["bg"]), float(i["mix"])
    out = np.concatenate([fg[:3] * fg[3] + bg[:3] * (1.0 - fg[3]), [fg[3] + bg[3] * (1.0 - fg[3])]])
    return _as(m * out + (1.0 - m) * bg, t)


def _disjointover(i, t):
    """``mx_disjointover_color4``."""
    fg, bg, m = _vec(i["fg"]), _vec(i["bg"]), float(i["mix"])
    summed = fg[3] + bg[3]
    if summed <= 1.0:
        rgb = fg[:3] + bg[:3]
    elif abs(bg[3]) < _EPS:
        rgb = np.zeros(3)
    else:
        rgb = fg[:3] + bg[:3] * ((1.0 - fg[3]) / bg[3])
    out = np.concatenate([rgb, [min(summed, 1.0)]])
    return _as(out * m + (1.0 - m) * bg, t)


OPS = {
    "dot": lambda i, t: _as(i["in"], t),
    "constant": lambda i, t: _as(i["value"], t),
    "convert": lambda i, t: _as(i["in"], t),
    "multiply": lambda i, t: _as(_num(i["in1"]) * _num(i["in2"]), t),
    "add": lambda i, t: _as(_num(i["in1"]) + _num(i["in2"]), t),
    "subtract": lambda i, t: _as(_num(i["in1"]) - _num(i["in2"]), t),
    "divide": lambda i, t: _as(_divide(i["in1"], i["in2"]), t),
    "modulo": lambda i, t: _as(_mod(i["in1"], i["in2"]), t),
    "fract": _unary(lambda v: v - np.floor(v)),
    "floor": _unary(np.floor),
    "ceil": _unary(np.ceil),
    "round": _unary(_round),
    "sign": _unary(np.sign),
    "absval": _unary(np.abs),
    "sqrt": _unary(np.sqrt),
    "exp": _unary(np.exp),
    "ln": _unary(np.log),
    "sin": _unary(np.sin),
    "cos": _unary(np.cos),
    "tan": _unary(np.tan),
    "asin": _unary(np.arcsin),
    "acos": _unary(np.arccos),
    "atan2": lambda i, t: _as(np.arctan2(_num(i["iny"]), _num(i["inx"])), t),
    "mix": lambda i, t: _as(_num(i["fg"]) * _num(i["mix"]) + _num(i["bg"]) * (1.0 - _num(i["mix"])), t),
    "max": lambda i, t: _as(np.maximum(_num(i["in1"]), _num(i["in2"])), t),
    "min": lambda i, t: _as(np.minimum(_num(i["in1"]), _num(i["in2"])), t),
    "clamp": lambda i, t: _as(np.minimum(np.maximum(_num(i["in"]), _num(i["low"])), _num(i["high"])), t),
    "power": lambda i, t: _as(np.power(_num(i["in1"]), _num(i["in2"])), t),
    "invert": lambda i, t: _as(_num(i["amount"]) - _num(i["in"]), t),
    "remap": lambda i, t: _as(
        _num(i["outlow"])
        + (_num(i["in"]) - _num(i["inlow"]))
        * (_num(i["outhigh"]) - _num(i["outlow"]))
        / (_num(i["inhigh"]) - _num(i["inlow"])),
        t,
    ),
    "smoothstep": _smoothstep,
    "magnitude": lambda i, t: float(np.linalg.norm(_vec(i["in"]))),
    "normalize": _normalize,
    "dotproduct": lambda i, t: float(np.dot(_vec(i["in1"]), _vec(i["in2"]))),
    "crossproduct": lambda i, t: _as(np.cross(_vec(i["in1"])[:3], _vec(i["in2"])[:3]), t),
    "extract": lambda i, t: float(_vec(i["in"])[int(i["index"])]),
    "combine2": lambda i, t: (
        _as([float(i["in1"]), float(i["in2"])], t)
        if not isinstance(i["in1"], np.ndarray)
        else _as(np.concatenate([_vec(i["in1"]), _vec(i["in2"])]), t)
    ),
    "combine3": lambda i, t: _as([float(i["in1"]), float(i["in2"]), float(i["in3"])], t),
    "combine4": lambda i, t: _as([float(i["in1"]), float(i["in2"]), float(i["in3"]), float(i["in4"])], t),
    "ifgreater": _if_bool(lambda a, b: a > b),
    "ifgreatereq": _if_bool(lambda a, b: a >= b),
    "ifequal": _if_bool(lambda a, b: a == b),
    "and": lambda i, t: bool(i["in1"]) and bool(i["in2"]),
    "or": lambda i, t: bool(i["in1"]) or bool(i["in2"]),
    "not": lambda i, t: not bool(i["in"]),
    "rotate2d": _rotate2d,
    "rotate3d": _rotate3d,
    "switch": _switch,
    "luminance": _luminance,
    "rgbtohsv": _colour_fn(_rgbtohsv_3),
    "hsvtorgb": _colour_fn(_hsvtorgb_3),
    "ramplr": _ramp(0, "valuel", "valuer"),
    "ramptb": _ramp(1, "valueb", "valuet"),
    "splitlr": _split(0, "valuel", "valuer"),
    "splittb": _split(1, "valueb", "valuet"),
    "plus": _mixer(lambda fg, bg: bg + fg),
    "minus": _mixer(lambda fg, bg: bg - fg),
    "difference": _mixer(lambda fg, bg: np.abs(bg - fg)),
    "screen": _mixer(lambda fg, bg: 1.0 - (1.0 - fg) * (1.0 - bg)),
    "burn": _burn_dodge(_burn),
    "dodge": _burn_dodge(_dodge),
    "inside": lambda i, t: _as(_num(i["in"]) * _num(i["mask"]), t),
    "outside": lambda i, t: _as(_num(i["in"]) * (1.0 - _num(i["mask"])), t),
    "premult": _premult,
    "unpremult": _unpremult,
    "over": _composite(lambda fa, ba: 1.0, lambda fa, ba: 1.0 - fa),
    "in": _composite(lambda fa, ba: ba, lambda fa, ba: 0.0),
    "out": _composite(lambda fa, ba: 1.0 - ba, lambda fa, ba: 0.0),
    "mask": _composite(lambda fa, ba: 0.0, lambda fa, ba: fa),
    "matte": _matte,
    "disjointover": _disjointover,
}


def finite(value: Any) -> bool:
    """Whether a value is finite (non-numbers count as finite).

    Examples
    --------
    >>> finite(1.0), finite(float("nan")), finite("a")
    (True, False, True)
    """
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, (np.ndarray, tuple, list)):
        try:
            return bool(np.all(np.isfinite(np.asarray(value, dtype=np.float64))))
        except (TypeError, ValueError):
            return True
    if isinstance(value, (float, np.floating)):
        return bool(np.isfinite(value))
    return True


def apply(category: str, inputs: dict, out_type: str) -> Any:
    """The value of a ``category`` node with resolved ``inputs``; KeyError if not in OPS.

    Where the operation is undefined (ln of 0, sqrt of a negative number, remap with
    inlow = inhigh) the value is NaN or infinite, as in GLSL: a graph may compute it in a
    branch it does not select.  The readers fail a material whose *input* ends up not finite.

    Examples
    --------
    >>> apply("mix", {"fg": 1.0, "bg": 0.0, "mix": 0.25}, "float")
    0.25
    >>> apply("multiply", {"in1": (0.5, 0.5, 0.5), "in2": 0.5}, "color3").tolist()
    [0.25, 0.25, 0.25]
    >>> [round(float(x), 12) for x in apply("rotate2d", {"in": (1.0, 0.0), "amount": 90.0}, "vector2")]
    [0.0, -1.0]
    >>> apply("modulo", {"in1": -0.25, "in2": 1.0}, "float")
    0.75
    """
    with np.errstate(all="ignore"):
        return OPS[category](inputs, out_type)


__all__ = ["OPS", "apply", "finite"]
