"""The MaterialX data library, loaded once: nodedefs, their defaults and implementations.

usd-core has no shader registry for MaterialX ``ND_`` nodes, so defaults of every node
(``ND_open_pbr_surface_surfaceshader``, ``ND_standard_surface_surfaceshader``,
``ND_UsdPreviewSurface_surfaceshader``, ``ND_image_color3``, ...) come from here.
"""

from __future__ import annotations

import functools
import os
import re
import struct
from collections.abc import Callable
from typing import Any

from ..nodes.materialx_defs import parse_value


@functools.lru_cache(maxsize=1)
def library():
    """The MaterialX standard data library as a Document (loaded on first use)."""
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib


def nodedef(name: str) -> Any:
    """The library nodedef ``name`` or None."""
    return library().getNodeDef(name)


def _local(name: str, nd: Any) -> bool:
    """Whether ``nd`` is a nodedef of a user's document rather than of the data library."""
    return nd is not None and library().getNodeDef(name) is None


def inputs(name: str, nd: Any = None) -> dict:
    """{input name: (type, default value, defaultgeomprop)} of nodedef ``name`` (library order).

    ``nd``: the nodedef element itself, for a nodedef defined in a user's document (looked
    up there first: the data library does not know it).  Raises LookupError if neither has it.

    Examples
    --------
    >>> inputs("ND_image_color3")["texcoord"][2]
    'UV0'
    """
    return _described(name, nd, _inputs_of)


def _described(name: str, nd: Any, describe: Callable[[Any], dict]) -> dict:
    """``describe`` of nodedef ``name``: of ``nd`` when it is a document's own nodedef, else of
    the data library's (cached; LookupError if the library has no such nodedef)."""
    if _local(name, nd):
        return describe(nd)
    return _library_described(name, describe)


@functools.cache
def _library_described(name: str, describe: Callable[[Any], dict]) -> dict:
    nd = nodedef(name)
    if nd is None:
        raise LookupError(f"the MaterialX data library has no nodedef {name!r}")
    return describe(nd)


def _inputs_of(nd: Any) -> dict:
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


@functools.cache
def default_parameters(name):
    """{input name: Parameter(default, "default of <nodedef>", "default")} of the non-geometry
    inputs of nodedef ``name`` (shared, immutable)."""
    from .material import Parameter

    prov = f"default of {name}"
    return {n: Parameter(v, prov, "default") for n, (t, v, g) in inputs(name).items() if not g}


def outputs(name: str, nd: Any = None) -> dict:
    """{output name: type} of nodedef ``name`` (``nd``: a document's own nodedef element).

    Raises LookupError if the nodedef is unknown.

    Examples
    --------
    >>> outputs("ND_image_color3")
    {'out': 'color3'}
    """
    return _described(name, nd, _outputs_of)


def _outputs_of(nd: Any) -> dict:
    outs = {o.getName(): o.getType() for o in nd.getActiveOutputs()}
    return outs or {"out": nd.getType()}


@functools.cache
def category(name: str) -> str | None:
    """The node category (e.g. "multiply") of nodedef ``name``, or None if unknown."""
    nd = nodedef(name)
    return nd.getNodeString() if nd is not None else None


def implementation_graph(name: str, nd: Any = None) -> Any:
    """The nodegraph implementing nodedef ``name`` (the library's, or for a document's own
    nodedef ``nd`` the document's), or None."""
    if _local(name, nd):
        return _graph_of(nd, nd.getDocument())
    return _library_graph(name)


@functools.cache
def _library_graph(name: str) -> Any:
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


@functools.cache
def _unit_converter(unittype: str) -> Any:
    """MaterialX's own ``LinearUnitConverter`` of a unit type of the data library (None if unknown)."""
    import MaterialX as mx

    typedef = library().getUnitTypeDef(unittype)
    return mx.LinearUnitConverter.create(typedef) if typedef is not None else None


@functools.cache
def base_unit(unittype: str) -> str:
    """The unit of scale 1 of a unit type of the data library ("meter", "degree"), or "".

    Examples
    --------
    >>> base_unit("distance"), base_unit("angle")
    ('meter', 'degree')
    """
    for unitdef in library().getUnitDefs():
        if unitdef.getUnitType() == unittype:
            for unit in unitdef.getUnits():
                if float(unit.getAttribute("scale") or "nan") == 1.0:
                    return unit.getName()
    return ""


def target_unit(elem: Any) -> str:
    """The unit a value with a ``unit`` is converted to, as MaterialX's shader generation
    chooses it: the unit of the nodedef's input (``getActiveUnit``, e.g. degree for
    ``rotate2d``'s amount), else the global target -- the unit type's unit of scale 1
    (meter, the distance unit MaterialX's viewer and test renders target; degree)."""
    return elem.getActiveUnit() or base_unit(elem.getUnitType())


def convert_unit(elem: Any, value: Any) -> tuple[Any, str]:
    """``(value in the target unit, note)`` of an element with ``unit`` / ``unittype``
    (float or tuple of floats), converted by MaterialX's ``LinearUnitConverter``; the value
    unchanged with an empty note when it has no unit.  ValueError for an unknown unit.

    Examples
    --------
    >>> import MaterialX as mx
    >>> doc = mx.createDocument()
    >>> i = doc.addNode("constant", "c", "float").addInput("value", "float")
    >>> i.setValueString("75"); i.setUnit("centimeter"); i.setUnitType("distance")
    >>> convert_unit(i, 75.0)
    (0.75, '75 centimeter -> 0.75 meter')
    """
    if not elem.hasUnit():
        return value, ""
    unit, unittype = elem.getUnit(), elem.getUnitType() or "distance"
    conv = _unit_converter(unittype)
    if conv is None:
        raise ValueError(f"{elem.getNamePath()}: unit type {unittype!r} is not defined by the MaterialX library")
    target = target_unit(elem) if elem.getUnitType() else base_unit(unittype)
    for u in (unit, target):
        if conv.getUnitAsInteger(u) < 0:
            raise ValueError(f"{elem.getNamePath()}: {u!r} is not a {unittype} unit of the MaterialX library")
    if unit == target:
        return value, ""
    if isinstance(value, tuple):
        out = tuple(conv.convert(float(x), unit, target) for x in value)
    else:
        out = conv.convert(float(value), unit, target)
    show = (lambda v: "(" + ", ".join(f"{x:g}" for x in v) + ")") if isinstance(value, tuple) else "{:g}".format
    return out, f"{show(value)} {unit} -> {show(out)} {target}"


def source_folder(file: str, uri: str, doc: Any = None) -> str:
    """The folder of the document an element was read from, given its source URI.

    Parameters
    ----------
    file : str
        The document that was read (``readFromXmlFile``).
    uri : str
        The element's ``getActiveSourceUri()``: empty or ``file`` itself for its own elements,
        absolute for the data library's, and for an ``xi:include``d document its ``href`` as
        written (relative to the document that includes it).
    doc : MaterialX Document, optional
        The document read: the source URIs of its elements name the included documents, whose
        folders are searched too (nested includes), as MaterialX's reader searches them.

    Examples
    --------
    >>> source_folder("/a/b/look.mtlx", "")
    '/a/b'
    >>> source_folder("/a/b/look.mtlx", "/lib/stdlib_defs.mtlx")
    '/lib'
    >>> source_folder("/a/b/look.mtlx", "sub/inc.mtlx")   # not found: relative to the document read
    '/a/b/sub'
    >>> import os
    >>> source_folder("b/look.mtlx", "b/look.mtlx") == os.path.abspath("b")   # the document itself, named relatively
    True
    """
    root = os.path.dirname(os.path.abspath(file))
    # the document's own elements carry the path it was read with (relative to the working
    # directory when the file was named so), not an include's href
    if not uri or uri == file or (doc is not None and uri == doc.getSourceUri()):
        return root
    if os.path.isabs(uri):
        return os.path.dirname(os.path.normpath(uri))
    for folder in _include_folders(os.path.abspath(file), doc):
        cand = os.path.join(folder, uri)
        if os.path.isfile(cand):
            return os.path.dirname(os.path.normpath(cand))
    return os.path.dirname(os.path.normpath(os.path.join(root, uri)))


def _include_folders(file: str, doc: Any) -> list:
    """Folders of ``file`` and of the documents it includes (found from its elements'
    source URIs, each looked up in the folders found before it)."""
    folders = [os.path.dirname(file)]
    if doc is None:
        return folders
    uris = sorted(u for u in {e.getSourceUri() for e in doc.traverseTree()} - {"", file} if not os.path.isabs(u))
    changed = True
    while changed and uris:
        changed = False
        for u in list(uris):
            for folder in folders:
                cand = os.path.join(folder, u)
                if os.path.isfile(cand):
                    d = os.path.dirname(os.path.normpath(cand))
                    if d not in folders:
                        folders.append(d)
                    uris.remove(u)
                    changed = True
                    break
    return folders


#: A number at the start of a text, as C++ stream extraction (MaterialX's value reader) reads it.
_LEADING_NUMBER = re.compile(r"\s*[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


def mx_value(elem: Any, type_name: str, notes: list[str] | None = None) -> Any:
    """The value of a MaterialX input / output element as parsed by MaterialX itself
    (``getValue``: "1 0 0" and "1, 0, 0" alike), as a Python value: float, int, bool, str
    or a tuple of floats; None when nothing (or nothing MaterialX can parse) is authored.

    A float whose text is more than one number ("0.482,0.169,0.109", "1.0.0") is read as
    MaterialX reads it, its leading number, when ``notes`` is given (a line saying so is
    appended to it); without ``notes`` it raises ValueError.

    Examples
    --------
    >>> import MaterialX as mx
    >>> doc = mx.createDocument()  # kept: a node of a collected document is orphaned
    >>> n = doc.addNode("constant", "c", "color3")
    >>> i = n.addInput("value", "color3"); i.setValueString("1 0 0.5")
    >>> mx_value(i, "color3")
    (1.0, 0.0, 0.5)
    >>> f = n.addInput("f", "float"); f.setValueString("0.482,0.169,0.109")
    >>> notes = []
    >>> mx_value(f, "float", notes), notes
    (0.482, ["float value '0.482,0.169,0.109' is not one number: read as 0.482, its leading number, as MaterialX reads it"])
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
        except ValueError:  # MaterialX reads a leading number ("1.0.0" as 1)
            if notes is None:
                raise ValueError(f"float value {text!r} is not a number") from None
        lead = _LEADING_NUMBER.match(text)
        x = float(lead.group()) if lead else float(v)
        if struct.unpack("f", struct.pack("f", x))[0] != struct.unpack("f", struct.pack("f", float(v)))[0]:
            x = float(v)  # not the number MaterialX read: MaterialX's own value
        notes.append(
            f"float value {text!r} is not one number: read as {x:g}, its leading number, as MaterialX reads it"
        )
        return x
    vals = tuple(float(x) for x in v)
    try:  # MaterialX separates components by commas and/or spaces; read them in double precision
        exact = tuple(float(x) for x in re.split(r"[,\s]+", text.strip()))
    except ValueError:
        raise ValueError(f"{type_name} value {text!r} has a component that is not a number") from None
    if len(exact) == len(vals):
        vals = exact
    if type_name.startswith(("color", "vector")) and len(vals) != int(type_name[-1]):
        raise ValueError(f"{type_name} value {elem.getValueString()!r} has {len(vals)} components")
    return vals


__all__ = [
    "library",
    "nodedef",
    "inputs",
    "outputs",
    "category",
    "implementation_graph",
    "mx_value",
    "source_folder",
    "convert_unit",
    "target_unit",
    "base_unit",
]
