"""The MaterialX data library, loaded once: nodedefs, their defaults and implementations.

usd-core has no shader registry for MaterialX ``ND_`` nodes, so defaults of every node
(``ND_open_pbr_surface_surfaceshader``, ``ND_standard_surface_surfaceshader``,
``ND_UsdPreviewSurface_surfaceshader``, ``ND_image_color3``, ...) come from here.
"""
import functools
import re

from ..nodes.materialx_defs import parse_value


@functools.lru_cache(maxsize=1)
def library():
    """The MaterialX standard data library as a Document (loaded on first use)."""
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib


def nodedef(name: str):
    """The library nodedef ``name`` or None."""
    return library().getNodeDef(name)


def _local(name: str, nd) -> bool:
    """Whether ``nd`` is a nodedef of a user's document rather than of the data library."""
    return nd is not None and library().getNodeDef(name) is None


def inputs(name: str, nd=None) -> dict:
    """{input name: (type, default value, defaultgeomprop)} of nodedef ``name`` (library order).

    ``nd``: the nodedef element itself, for a nodedef defined in a user's document (looked
    up there first: the data library does not know it).  Raises LookupError if neither has it.

    Examples
    --------
    >>> inputs("ND_image_color3")["texcoord"][2]
    'UV0'
    """
    if _local(name, nd):
        return _inputs_of(nd)
    return _library_inputs(name)


@functools.lru_cache(maxsize=None)
def _library_inputs(name: str) -> dict:
    nd = nodedef(name)
    if nd is None:
        raise LookupError(f"the MaterialX data library has no nodedef {name!r}")
    return _inputs_of(nd)


def _inputs_of(nd) -> dict:
    out = {}
    for i in nd.getActiveInputs():
        t = i.getType()
        try:
            v = mx_value(i, t)
        except (ValueError, TypeError):
            v = i.getValueString()
        if v is None and t in ("color3", "color4", "vector2", "vector3", "vector4", "float", "integer", "boolean"):
            v = parse_value(t, i.getValueString()) if i.getValueString() else None
        out[i.getName()] = (t, v, i.getDefaultGeomPropString())
    return out


@functools.lru_cache(maxsize=None)
def default_parameters(name):
    """{input name: Parameter(default, "default of <nodedef>", "default")} of the non-geometry
    inputs of nodedef ``name`` (shared, immutable)."""
    from .material import Parameter

    prov = f"default of {name}"
    return {n: Parameter(v, prov, "default") for n, (t, v, g) in inputs(name).items() if not g}


def outputs(name: str, nd=None) -> dict:
    """{output name: type} of nodedef ``name`` (``nd``: a document's own nodedef element).

    Raises LookupError if the nodedef is unknown.

    Examples
    --------
    >>> outputs("ND_image_color3")
    {'out': 'color3'}
    """
    if _local(name, nd):
        return _outputs_of(nd)
    return _library_outputs(name)


@functools.lru_cache(maxsize=None)
def _library_outputs(name: str) -> dict:
    nd = nodedef(name)
    if nd is None:
        raise LookupError(f"the MaterialX data library has no nodedef {name!r}")
    return _outputs_of(nd)


def _outputs_of(nd) -> dict:
    outs = {o.getName(): o.getType() for o in nd.getActiveOutputs()}
    return outs or {"out": nd.getType()}


@functools.lru_cache(maxsize=None)
def category(name: str):
    """The node category (e.g. "multiply") of nodedef ``name``, or None if unknown."""
    nd = nodedef(name)
    return nd.getNodeString() if nd is not None else None


def implementation_graph(name: str, nd=None):
    """The nodegraph implementing nodedef ``name`` (the library's, or for a document's own
    nodedef ``nd`` the document's), or None."""
    if _local(name, nd):
        return _graph_of(nd, nd.getDocument())
    return _library_graph(name)


@functools.lru_cache(maxsize=None)
def _library_graph(name: str):
    nd = nodedef(name)
    if nd is None:
        return None
    return _graph_of(nd, library())


def _graph_of(nd, doc):
    import MaterialX as mx

    impl = nd.getImplementation()
    if impl is not None and impl.isA(mx.NodeGraph):
        return impl
    name = nd.getName()
    for ng in doc.getNodeGraphs():
        if ng.getNodeDefString() == name:
            return ng
    return None


def mx_value(elem, type_name: str):
    """The value of a MaterialX input / output element as parsed by MaterialX itself
    (``getValue``: "1 0 0" and "1, 0, 0" alike), as a Python value: float, int, bool, str
    or a tuple of floats; None when nothing (or nothing MaterialX can parse) is authored.

    Examples
    --------
    >>> import MaterialX as mx
    >>> doc = mx.createDocument()  # kept: a node of a collected document is orphaned
    >>> n = doc.addNode("constant", "c", "color3")
    >>> i = n.addInput("value", "color3"); i.setValueString("1 0 0.5")
    >>> mx_value(i, "color3")
    (1.0, 0.0, 0.5)
    """
    if type_name in ("string", "filename"):
        text = elem.getValueString()
        return text if text != "" else None
    v = elem.getValue()
    if v is None:
        return None
    text = elem.getValueString()
    if isinstance(v, (bool, int, float, str)):
        if type_name != "float":
            return v
        try:  # the decimal text in double precision (MaterialX holds floats in single precision)
            return float(text)
        except ValueError:
            return float(v)
    vals = tuple(float(x) for x in v)
    try:  # MaterialX separates components by commas and/or spaces; read them in double precision
        exact = tuple(float(x) for x in re.split(r"[,\s]+", text.strip()))
        if len(exact) == len(vals):
            vals = exact
    except ValueError:
        pass
    if type_name.startswith(("color", "vector")) and len(vals) != int(type_name[-1]):
        raise ValueError(f"{type_name} value {elem.getValueString()!r} has {len(vals)} components")
    return vals


__all__ = ["library", "nodedef", "inputs", "outputs", "category", "implementation_graph", "mx_value"]
