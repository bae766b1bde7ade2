"""The MaterialX data library, loaded once: nodedefs, their defaults and implementations.

usd-core has no shader registry for MaterialX ``ND_`` nodes, so defaults of every node
(``ND_open_pbr_surface_surfaceshader``, ``ND_standard_surface_surfaceshader``,
``ND_UsdPreviewSurface_surfaceshader``, ``ND_image_color3``, ...) come from here.
"""
import functools

from ..nodes.materialx_defs import parse_value


@functools.lru_cache(maxsize=1)
def library():
    """The MaterialX standard data library as a Document (loaded on first use)."""
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib


def nodedef(name):
    """The library nodedef ``name`` or None."""
    return library().getNodeDef(name)


@functools.lru_cache(maxsize=None)
def inputs(name):
    """{input name: (type, default value, defaultgeomprop)} of nodedef ``name`` (library order).

    Raises LookupError if the library has no such nodedef.
    """
    nd = nodedef(name)
    if nd is None:
        raise LookupError(f"the MaterialX data library has no nodedef {name!r}")
    out = {}
    for i in nd.getActiveInputs():
        t = i.getType()
        try:
            v = parse_value(t, i.getValueString())
        except ValueError:
            v = i.getValueString()
        out[i.getName()] = (t, v, i.getDefaultGeomPropString())
    return out


@functools.lru_cache(maxsize=None)
def default_parameters(name):
    """{input name: Parameter(default, "default of <nodedef>", "default")} of the non-geometry
    inputs of nodedef ``name`` (shared, immutable)."""
    from .material import Parameter

    prov = f"default of {name}"
    return {n: Parameter(v, prov, "default") for n, (t, v, g) in inputs(name).items() if not g}


@functools.lru_cache(maxsize=None)
def outputs(name):
    """{output name: type} of nodedef ``name``."""
    nd = nodedef(name)
    return {o.getName(): o.getType() for o in nd.getActiveOutputs()}


@functools.lru_cache(maxsize=None)
def category(name):
    """The node category (e.g. "multiply") of nodedef ``name``, or None if unknown."""
    nd = nodedef(name)
    return nd.getNodeString() if nd is not None else None


@functools.lru_cache(maxsize=None)
def implementation_graph(name):
    """The nodegraph implementing nodedef ``name`` in the library, or None."""
    import MaterialX as mx

    nd = nodedef(name)
    if nd is None:
        return None
    impl = nd.getImplementation()
    if impl is not None and impl.isA(mx.NodeGraph):
        return impl
    for ng in library().getNodeGraphs():
        if ng.getNodeDefString() == name:
            return ng
    return None


__all__ = ["library", "nodedef", "inputs", "outputs", "category", "implementation_graph"]
