"""Values of the MaterialX stdlib nodes the readers evaluate on the CPU, at one point.

A table, not an if-chain: node category -> function(inputs, out_type) -> value, where
``inputs`` holds the node's resolved input values by name (floats, or float64 arrays for
colorN/vectorN) and ``out_type`` is the node's output type.  The semantics are those of the
MaterialX 1.39 specification (Standard Nodes); nodes not in the table (noise, closures,
geometric nodes other than texcoord) are reported as unsupported by the readers.
"""

import numpy as np


def _as(v, out_type):
    """Broadcast a value to ``out_type`` (float -> colorN/vectorN like MaterialX's convert)."""
    if out_type in ("float", "integer", "boolean", "string", "filename"):
        if isinstance(v, np.ndarray):
            return float(v.reshape(-1)[0])
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
    return np.asarray(v, dtype=np.float64) if isinstance(v, (tuple, list, np.ndarray)) else float(v)


def _divide(a, b):
    a, b = _num(a), _num(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(np.asarray(b) != 0.0, np.asarray(a) / np.where(np.asarray(b) != 0.0, b, 1.0), 0.0)
    return q


def _if(cmp):
    return lambda i, t: _as(
        i["in1"] if cmp(float(_as(i["value1"], "float")), float(_as(i["value2"], "float"))) else i["in2"], t
    )


def _rotate2d(i, t):
    """MaterialX ``rotate2d``: (c x + s y, -s x + c y) with amount in degrees (its GLSL
    implementation ``mx_rotate_vector2``; a positive amount turns the vector clockwise)."""
    x, y = np.asarray(_num(i["in"]), dtype=np.float64).reshape(-1)[:2]
    a = np.radians(float(i["amount"]))
    c, s = np.cos(a), np.sin(a)
    return _as(np.array([c * x + s * y, -s * x + c * y]), t)


def _switch(i, t):
    """MaterialX ``switch``: ``which`` 0 selects in1, 1 in2, ... (floored, clamped to the inputs)."""
    names = sorted((n for n in i if n.startswith("in") and n[2:].isdigit()), key=lambda n: int(n[2:]))
    k = min(max(int(np.floor(float(i["which"]))), 0), len(names) - 1)
    return _as(i[names[k]], t)


OPS = {
    "dot": lambda i, t: _as(i["in"], t),
    "constant": lambda i, t: _as(i["value"], t),
    "convert": lambda i, t: _as(i["in"], t),
    "multiply": lambda i, t: _as(_num(i["in1"]) * _num(i["in2"]), t),
    "add": lambda i, t: _as(_num(i["in1"]) + _num(i["in2"]), t),
    "subtract": lambda i, t: _as(_num(i["in1"]) - _num(i["in2"]), t),
    "divide": lambda i, t: _as(_divide(i["in1"], i["in2"]), t),
    "mix": lambda i, t: _as(_num(i["fg"]) * _num(i["mix"]) + _num(i["bg"]) * (1.0 - _num(i["mix"])), t),
    "max": lambda i, t: _as(np.maximum(_num(i["in1"]), _num(i["in2"])), t),
    "min": lambda i, t: _as(np.minimum(_num(i["in1"]), _num(i["in2"])), t),
    "clamp": lambda i, t: _as(np.minimum(np.maximum(_num(i["in"]), _num(i["low"])), _num(i["high"])), t),
    "power": lambda i, t: _as(np.power(_num(i["in1"]), _num(i["in2"])), t),
    "invert": lambda i, t: _as(_num(i["amount"]) - _num(i["in"]), t),
    "absval": lambda i, t: _as(np.abs(_num(i["in"])), t),
    "dotproduct": lambda i, t: float(np.dot(_num(i["in1"]), _num(i["in2"]))),
    "extract": lambda i, t: float(np.asarray(_num(i["in"])).reshape(-1)[int(i["index"])]),
    "combine2": lambda i, t: _as([float(i["in1"]), float(i["in2"])], t),
    "combine3": lambda i, t: _as([float(i["in1"]), float(i["in2"]), float(i["in3"])], t),
    "combine4": lambda i, t: _as([float(i["in1"]), float(i["in2"]), float(i["in3"]), float(i["in4"])], t),
    "ifgreater": _if(lambda a, b: a > b),
    "ifgreatereq": _if(lambda a, b: a >= b),
    "ifequal": _if(lambda a, b: a == b),
    "rotate2d": _rotate2d,
    "switch": _switch,
}


def apply(category, inputs, out_type):
    """The value of a ``category`` node with resolved ``inputs``; KeyError if not in OPS.

    Examples
    --------
    >>> apply("mix", {"fg": 1.0, "bg": 0.0, "mix": 0.25}, "float")
    0.25
    >>> apply("multiply", {"in1": (0.5, 0.5, 0.5), "in2": 0.5}, "color3").tolist()
    [0.25, 0.25, 0.25]
    >>> [round(float(x), 12) for x in apply("rotate2d", {"in": (1.0, 0.0), "amount": 90.0}, "vector2")]
    [0.0, -1.0]
    """
    return OPS[category](inputs, out_type)


__all__ = ["OPS", "apply"]
