"""Node interfaces read from the MaterialX data library (the interface is data, not retyped).

``nodedef_inputs(name)`` returns the inputs of a MaterialX nodedef -- name, type, default
value, ``defaultgeomprop``, ``uniform`` and the ui ranges -- read from the MaterialX
Python package's own standard library (``mx.loadLibraries`` on the default data library
folders), imported lazily.  If MaterialX is not importable the same information comes from
``data/materialx_nodedefs.json``, a snapshot written from the library by
``tools/make_nodedef_snapshot.py`` (its header records the MaterialX version).  Both
sources go through the same parser of MaterialX value strings.
"""

import functools
import json
import os
from dataclasses import dataclass
from typing import Any

#: The nodedefs the shading nodes mirror (the snapshot holds exactly these).
NODEDEFS = ("ND_oren_nayar_diffuse_bsdf", "ND_open_pbr_surface_surfaceshader")

SNAPSHOT_FILE = os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data", "materialx_nodedefs.json"
)

_ATTRS = ("uimin", "uimax", "uisoftmin", "uisoftmax")


@dataclass(frozen=True)
class InputDef:
    """One input of a MaterialX nodedef.

    ``default`` is the parsed value (float, bool, int, str or a tuple of floats for
    colorN/vectorN) or None when the input has no value but a ``defaultgeomprop``
    (e.g. ``Nworld``: the geometric normal supplied by the renderer).
    """

    name: str
    type: str
    default: object
    defaultgeomprop: str
    uniform: bool
    uimin: object
    uimax: object
    uisoftmin: object
    uisoftmax: object


def parse_value(type_name: str, text: str | None) -> float | int | bool | str | tuple[float, ...] | None:
    """A MaterialX value string of ``type_name`` as a Python value (None for '')."""
    if text is None or text == "":
        return None
    if type_name == "float":
        return float(text)
    if type_name == "integer":
        return int(text)
    if type_name == "boolean":
        if text not in ("true", "false"):
            raise ValueError(f"bad boolean value {text!r}")
        return text == "true"
    if type_name.startswith(("color", "vector")):
        vals = tuple(float(v) for v in text.split(","))
        want = int(type_name[-1])
        if len(vals) != want:
            raise ValueError(f"{type_name} value {text!r} has {len(vals)} components")
        return vals
    return text


def _records_from_materialx():
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    out = {}
    for nd_name in NODEDEFS:
        nd = lib.getNodeDef(nd_name)
        if nd is None:
            raise LookupError(f"MaterialX {mx.__version__} has no nodedef {nd_name}")
        out[nd_name] = {
            "node": nd.getNodeString(),
            "version": nd.getVersionString(),
            "inputs": [
                {
                    "name": i.getName(),
                    "type": i.getType(),
                    "value": i.getValueString(),
                    "defaultgeomprop": i.getDefaultGeomPropString(),
                    "uniform": i.getAttribute("uniform") == "true",
                    **{a: i.getAttribute(a) for a in _ATTRS},
                }
                for i in nd.getActiveInputs()
            ],
        }
    return out, f"MaterialX {mx.__version__} data library"


def _records_from_snapshot():
    with open(SNAPSHOT_FILE) as fh:
        snap = json.load(fh)
    return snap["nodedefs"], f"snapshot {os.path.basename(SNAPSHOT_FILE)} ({snap['source']})"


@functools.cache
def _records(prefer_materialx=True):
    if prefer_materialx:
        try:
            return _records_from_materialx()
        except ImportError:
            pass
    return _records_from_snapshot()


def _to_def(rec):
    t = rec["type"]
    return InputDef(
        rec["name"],
        t,
        parse_value(t, rec["value"]),
        rec["defaultgeomprop"],
        bool(rec["uniform"]),
        *(parse_value(t, rec[a]) if rec[a] else None for a in _ATTRS),
    )


def nodedef_inputs(name: str, *, source: str = "auto") -> dict[str, InputDef]:
    """Inputs of a nodedef, in library order, as ``{input name: InputDef}``.

    Parameters
    ----------
    name : str
        One of ``NODEDEFS``.
    source : {"auto", "materialx", "snapshot"}
        "auto" reads the MaterialX library when the package imports, else the snapshot.

    Examples
    --------
    >>> d = nodedef_inputs("ND_oren_nayar_diffuse_bsdf")
    >>> d["color"].type, d["color"].default
    ('color3', (0.18, 0.18, 0.18))
    """
    if name not in NODEDEFS:
        raise ValueError(f"name: nodedef {name!r} is not mirrored here; expected one of {', '.join(NODEDEFS)}")
    if source == "auto":
        recs, _ = _records(True)
    elif source == "materialx":
        recs, _ = _records_from_materialx()
    elif source == "snapshot":
        recs, _ = _records(False)
    else:
        raise ValueError(f"source must be 'auto', 'materialx' or 'snapshot'; got {source!r}")
    return {r["name"]: _to_def(r) for r in recs[name]["inputs"]}


def nodedef_source() -> str:
    """Where ``nodedef_inputs(..., source='auto')`` reads from (a short description)."""
    return _records(True)[1]


def snapshot_records() -> tuple[dict[str, Any], str]:
    """The nodedef records as written to the snapshot (used by the snapshot tool)."""
    return _records_from_materialx()
