"""The MaterialX graph evaluator: the value of an input at one surface point.

Value resolution follows the MaterialX 1.39 specification: an input's value is its
connection (``nodename`` / ``nodegraph`` + ``output``; the connected output is followed
whatever its name), else its ``interfacename`` (the enclosing nodegraph's input), else its
authored ``value`` (a value with a ``unit`` converted to the target unit by MaterialX's
``LinearUnitConverter``; a relative file name resolved against the document the element was
read from, after ``fileprefix``), else the nodedef default from the MaterialX data library.  Connected
nodes are evaluated at one surface point (``uv``): stdlib math nodes (``ops``), ``constant``,
``image`` (sampled with OpenImageIO, ``textures``) and every node whose nodedef is
implemented by a nodegraph in the library (e.g. ``tiledimage``, evaluated through that
graph).  Other nodes (noise, closures, geometry other than texcoord) are listed as
unsupported and the input falls back to its nodedef default.  Colours are converted from
their active ``colorspace`` to ACEScg (``colorspace``).  A connection cycle raises
ValueError naming the elements on the cycle.

The same evaluator runs MaterialX's own translation graph for Standard Surface
(``ND_standard_surface_to_open_pbr_surface``, see ``mapping``) and the library graphs of
``ND_`` nodes met in USD stages.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import colorspace, mxlib, ops, textures
from .material import Material, Parameter
from .mxlib import mx_value

#: Node output types the evaluator can produce (closures are not values).
VALUE_TYPES = ("float", "integer", "boolean", "string", "filename", "color3", "color4", "vector2", "vector3", "vector4")
_COLORS = ("color3", "color4")


#: Longest chain of connected nodes evaluated (deeper graphs fail their material with a
#: one-line error instead of exhausting the interpreter's stack).
MAX_CHAIN = 2000


@contextlib.contextmanager
def deep_stack(frames: int = 8 * MAX_CHAIN + 2000) -> Iterator[None]:
    """Raise the interpreter's recursion limit to at least ``frames`` while evaluating graphs
    (the evaluator recurses along connections; since Python 3.11 such frames do not use
    the C stack)."""
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, frames))
    try:
        yield
    finally:
        sys.setrecursionlimit(old)


def follow(file: str, trail: tuple, key: object, network: str = "graph", nodes: str = "nodes") -> tuple:
    """``trail + (key,)``: the connections followed so far, and ``key``.  ValueError naming the
    elements of a connection cycle, or when the chain is deeper than :data:`MAX_CHAIN`
    connected ``nodes`` (of the shading ``network``).

    Examples
    --------
    >>> follow("x.mtlx", ("node:a",), "node:b")
    ('node:a', 'node:b')
    >>> follow("x.mtlx", ("node:a", "node:b"), "node:a")
    Traceback (most recent call last):
    ...
    ValueError: x.mtlx: connection cycle: node:a -> node:b -> node:a
    """
    if len(trail) > 2 * MAX_CHAIN:
        raise ValueError(
            f"{file}: the shading {network} is deeper than {MAX_CHAIN} connected {nodes} (at {key}); not evaluated"
        )
    if key in trail:
        loop = list(trail[trail.index(key) :]) + [key]
        raise ValueError(f"{file}: connection cycle: {' -> '.join(str(k) for k in loop)}")
    return trail + (key,)


def to_python(v: Any) -> Any:
    """Evaluator value -> Parameter value (tuple of floats for arrays)."""
    if isinstance(v, np.ndarray):
        return tuple(float(x) for x in v.reshape(-1))
    if isinstance(v, np.floating):
        return float(v)
    return v


def convert_color(value: Any, type_name: str, space: str) -> Any:
    """A colorN value converted from ``space`` to the working space (alpha untouched)."""
    a = np.asarray(value, dtype=np.float64).reshape(-1)
    if type_name not in _COLORS or space == "raw" or space == colorspace.WORKING_SPACE:
        return a
    out = a.copy()
    out[:3] = colorspace.to_working(a[:3], space)
    return out


class Resolver:
    """Evaluates inputs of one MaterialX document at one uv.

    ``sink``: a Material whose ``warnings`` / ``unsupported`` collect what is met;
    ``default_space``: colour space of colours when the document names none.
    """

    def __init__(self, file: str | os.PathLike[str], uv: ArrayLike, default_space: str, sink: Material) -> None:
        self.file = str(file)
        self.uv = np.asarray(uv, dtype=np.float64)
        self.default_space = default_space
        self.sink = sink
        # node outputs already evaluated, per (node, output, interface context, library):
        # a graph that reads one node many times evaluates it once
        self._memo: dict[tuple, Any] = {}
        self._folders: dict[str, str] = {}  # source URI -> folder of that document
        self.via: list[str] = []  # document nodes whose library implementation graph is being evaluated

    # ----------------------------------------------------------------- helpers
    def _note(self, text, unsupported=False):
        if self.via:  # met inside a library implementation graph: name the document's node too
            text = f"{self.via[0]}: {text}"
        lst = self.sink.unsupported if unsupported else self.sink.warnings
        if text not in lst:
            lst.append(text)

    @contextlib.contextmanager
    def inside(self, what: str) -> Iterator[None]:
        """Notes made while evaluating the implementation graph of ``what`` (a node of the
        document) name it first."""
        self.via.append(what)
        try:
            yield
        finally:
            self.via.pop()

    def _space(self, elem):
        space = elem.getActiveColorSpace() or self.default_space
        try:
            return colorspace.canonical(space)
        except ValueError as exc:
            raise ValueError(f"{self.file}: {elem.getNamePath()}: {exc}") from None

    def _source_folder(self, elem: Any) -> str:
        """The folder of the document ``elem`` was read from: relative file names resolve
        against it (after MaterialX's ``fileprefix``, applied by ``getResolvedValueString``).

        MaterialX keeps an ``xi:include``d document's source URI as its ``href`` was written,
        relative to the including document; it is looked up, as MaterialX's reader looks an
        include up, in the folder of the document read and of the documents it includes.
        """
        uri = elem.getActiveSourceUri()
        if uri not in self._folders:
            self._folders[uri] = mxlib.source_folder(self.file, uri, elem.getDocument())
        return self._folders[uri]

    def _authored(self, port: Any, library: bool) -> Parameter:
        t = port.getType()
        text = port.getValueString()
        notes: list[str] = []
        try:
            raw = mx_value(port, t, notes)
        except ValueError as exc:
            raise ValueError(f"{self.file}: {port.getNamePath()}: {exc}") from None
        for note in notes:  # read as MaterialX reads it, said once per material
            who = f"material {self.sink.name}: " if self.sink.name else ""
            self._note(f"{self.file}: {who}{port.getNamePath()}: {note}")
        if raw is None and text.strip():
            raise ValueError(f"{self.file}: {port.getNamePath()}: bad {t} value {text!r} (MaterialX cannot parse it)")
        if t == "filename":
            resolved = port.getResolvedValueString() or raw
            if resolved and not os.path.isabs(resolved) and textures.is_packaged(self.file):
                # a document inside a package: its relative names are members of the package
                outer, inner = self.file[: self.file.index("[")], self.file[self.file.index("[") + 1 : -1]
                resolved = f"{outer}[{os.path.normpath(os.path.join(os.path.dirname(inner), resolved))}]"
            elif resolved and not os.path.isabs(resolved):
                folder = self._source_folder(port)
                resolved = os.path.normpath(os.path.join(folder, resolved))
            space = "raw" if library else self._space(port)
            return Parameter(resolved, f"file {raw}", "file", authored=space)
        if t in _COLORS and not library:
            space = self._space(port)
            value = convert_color(raw, t, space)
            prov = f"authored at {port.getNamePath()}" + (
                "" if space == colorspace.WORKING_SPACE else f" ({space} -> {colorspace.WORKING_SPACE})"
            )
            return Parameter(value, prov, "authored", authored=raw)
        prov = f"authored at {port.getNamePath()}"
        if port.hasUnit() and t in ("float", "vector2", "vector3", "vector4"):
            try:
                converted, note = mxlib.convert_unit(port, raw)
            except ValueError as exc:
                raise ValueError(f"{self.file}: {exc}") from None
            if note:
                return Parameter(_array(converted), f"{prov} ({note})", "authored", authored=raw)
        return Parameter(_array(raw), prov, "authored")

    # ----------------------------------------------------------------- ports
    def port(self, port: Any, trail: tuple = (), iface: dict | None = None, library: bool = False) -> Parameter | None:
        """Resolve an input or output element; None when nothing is set (use the default)."""
        trail = follow(self.file, trail, "port:" + port.getNamePath())
        if port.hasInterfaceName():
            name = port.getInterfaceName()
            if iface is not None:
                return iface.get(name)
            ii = port.getInterfaceInput() if hasattr(port, "getInterfaceInput") else None
            if ii is None:  # a nodedef's own implementation graph: its interface is the nodedef's
                graph = port.getParent()
                while graph is not None and graph.getCategory() != "nodegraph":
                    graph = graph.getParent()
                nd = graph.getNodeDef() if graph is not None else None
                ii = nd.getActiveInput(name) if nd is not None else None
            if ii is None:
                self._note(f"{port.getNamePath()}: interface input {name!r} does not exist; default used")
                return None
            p = self.port(ii, trail, None, library)
            if p is None:
                return None
            return Parameter(p.value, f"interface {ii.getNamePath()} <- {p.provenance}", _kind(p), p.authored)
        node = port.getConnectedNode()
        if node is not None:
            out = port.getConnectedOutput() if hasattr(port, "getConnectedOutput") else None
            outname = port.getOutputString()
            src = self._check_connection_type(port, node, out) if not library else ""
            via = ""
            if out is not None and out.getParent() is not None and out.getParent().getCategory() == "nodegraph":
                via = f"{out.getNamePath()} <- "
                outname = out.getOutputString()
            p = self.node_value(node, outname, trail, iface, library)
            if p is None:
                return None
            if src:
                p = self.convert(p, src, port.getType(), port.getNamePath())
            return Parameter(p.value, via + p.provenance, _kind(p), p.authored)
        if port.getNodeName() or port.getNodeGraphString():
            self._note(self._dangling(port) + "; default used")
            return None
        if port.hasValueString():
            if not port.getValueString().strip() and port.getType() not in ("string", "filename"):
                self._note(f"{port.getNamePath()}: empty value; default used")
                return None
            return self._authored(port, library)
        if (
            not library
            and port.getCategory() == "output"
            and port.getParent() is not None
            and port.getParent().getCategory() == "nodegraph"
        ):
            self._note(f"{port.getNamePath()} is connected to nothing; default used")
        return None

    def _dangling(self, port: Any) -> str:
        """What a connection that leads nowhere leads to (a missing node, nodegraph or output)."""
        where = port.getNamePath()
        graph_name = port.getNodeGraphString()
        if graph_name:
            parent = port.getParent()
            graph = None
            while parent is not None and graph is None:
                graph = parent.getChild(graph_name) if hasattr(parent, "getChild") else None
                if graph is not None and graph.getCategory() != "nodegraph":
                    graph = None
                parent = parent.getParent()
            if graph is None:
                return f"{where}: connected to nodegraph {graph_name!r}, which does not exist"
            outname = port.getOutputString()
            out = graph.getOutput(outname) if outname else None
            if out is None:
                return (
                    f"{where}: connected to output {outname!r} of nodegraph {graph_name!r}, which has no "
                    f"output {outname!r}"
                    if outname
                    else f"{where}: connected to nodegraph {graph_name!r} without naming an output"
                )
            if out.getNodeName():
                return f"{out.getNamePath()} is connected to {out.getNodeName()!r}, which does not exist"
            return f"{out.getNamePath()} is connected to nothing"
        return f"{where}: connected to {port.getNodeName()!r}, which does not exist"

    def _check_connection_type(self, port: Any, node: Any, out: Any) -> str:
        """The type of the output an input is connected to when it is not the input's own
        type ("" when they match), with a warning (MaterialX's validation reports it; the
        value is converted by :meth:`convert`)."""
        src = out.getType() if out is not None else node.getType()
        if src == "multioutput" or not src:
            nd = node.getNodeDef()
            name = port.getOutputString()
            if nd is None or not name:
                return ""
            o = nd.getActiveOutput(name)
            src = o.getType() if o is not None else ""
        want = port.getType()
        if src and want and src != want and src in VALUE_TYPES and want in VALUE_TYPES:
            self._note(
                f"{port.getNamePath()} ({want}) is connected to {node.getNamePath()}, a {src} output: "
                f"the value is converted by MaterialX's ND_convert_{src}_{want}"
            )
            return src
        return ""

    def convert(self, p: Parameter, src: str, want: str, where: str) -> Parameter:
        """A ``src`` value connected to a ``want`` input, converted as MaterialX's
        ``ND_convert_<src>_<want>`` node converts it (its library graph, e.g. vector2 -> color3
        is (x, y, 0)); ValueError naming the input when MaterialX has no such conversion.

        Examples
        --------
        >>> from openpbr_diffuse.readers.material import Material
        >>> r = Resolver("x.mtlx", (0.25, 0.75), "acescg", Material("", "", "", "", False))
        >>> r.convert(Parameter(np.array([0.25, 0.75]), "uv", "uv"), "vector2", "color3", "S/base_color").value.tolist()
        [0.25, 0.75, 0.0]
        """
        name = f"ND_convert_{src}_{want}"
        if mxlib.nodedef(name) is None:
            raise ValueError(
                f"{self.file}: {where} ({want}) is connected to a {src} output, and MaterialX has no "
                f"conversion from {src} to {want}"
            )
        value = np.asarray(p.value, dtype=np.float64) if isinstance(p.value, (tuple, list)) else p.value
        graph = mxlib.implementation_graph(name)
        out = graph.getOutput("out") or (graph.getOutputs() or [None])[0] if graph is not None else None
        q = self.port(out, (), {"in": Parameter(value, p.provenance, p.kind)}, True) if out is not None else None
        if q is not None:
            value = q.value
        else:  # natively implemented (no library graph)
            value = ops.apply("convert", {"in": value}, want)
        return Parameter(value, f"{p.provenance} (converted {src} -> {want} by {name})", p.kind, p.authored)

    # ----------------------------------------------------------------- nodes
    def node_value(
        self, node: Any, outname: str, trail: tuple = (), iface: dict | None = None, library: bool = False
    ) -> Parameter | None:
        """The value of output ``outname`` of ``node`` (None if the node is not evaluated)."""
        key = (node.getNamePath(), outname, id(iface), library)
        hit = self._memo.get(key)
        if hit is not None:
            return hit[0]
        p = self._node_value(node, outname, trail, iface, library)
        self._memo[key] = (p, iface)  # iface kept alive so that its id is not reused
        return p

    def _node_value(self, node: Any, outname: str, trail: tuple, iface: dict | None, library: bool) -> Parameter | None:
        trail = follow(self.file, trail, "node:" + node.getNamePath())
        nd = node.getNodeDef()
        cat = node.getCategory()
        if nd is None:
            self._note(
                f"node {node.getNamePath()} ({cat}, type {node.getType()}) has no nodedef in the "
                f"MaterialX library: not evaluated, default used",
                True,
            )
            return None
        ndname = nd.getName()
        if cat == "texcoord" and node.getType() == "vector2":
            return Parameter(
                self.uv.copy(), f"texcoord {node.getNamePath()} = uv ({self.uv[0]:g}, {self.uv[1]:g})", "uv"
            )
        outs = mxlib.outputs(ndname, nd)
        out_type = outs.get(outname) if outname else None
        if out_type is None:
            out_type = node.getType() if node.getType() != "multioutput" else next(iter(outs.values()))
            outname = outname or next(iter(outs))
        if out_type not in VALUE_TYPES:
            self._note(f"node {node.getNamePath()} ({ndname}) outputs a {out_type}: not a value", True)
            return None
        graph = mxlib.implementation_graph(ndname, nd)
        if cat not in ops.OPS and cat != "image" and graph is None:
            self._note(f"node {node.getNamePath()} ({ndname}) is not evaluated by the reader; default used", True)
            return None
        resolved = {}
        for name, (_t, default, geomprop) in mxlib.inputs(ndname, nd).items():
            inp = node.getInput(name)
            p = self.port(inp, trail, iface, library) if inp is not None else None
            if p is None:
                if geomprop in ("UV0", "UV1"):
                    p = Parameter(self.uv.copy(), f"uv ({self.uv[0]:g}, {self.uv[1]:g})", "uv")
                elif geomprop:
                    self._note(
                        f"node {node.getNamePath()} ({ndname}): input {name} needs geometry "
                        f"({geomprop}); not evaluated",
                        True,
                    )
                    return None
                else:
                    p = Parameter(default, f"default of {ndname}", "default")
            resolved[name] = p
        if cat == "image":
            return self.texture(node.getNamePath(), ndname, resolved, out_type)
        if graph is None:  # a natively implemented stdlib node (its library graph, if any, defines it)
            try:
                value = ops.apply(cat, {n: p.value for n, p in resolved.items()}, out_type)
            except (TypeError, ValueError, IndexError, KeyError, ArithmeticError) as exc:
                raise ValueError(f"{self.file}: node {node.getNamePath()} ({ndname}): {exc}") from None
            return Parameter(value, _describe(f"{cat} {node.getNamePath()}", resolved), _combined(resolved))
        out = graph.getOutput(outname) or (graph.getOutputs() or [None])[0]
        if out is None:
            raise ValueError(
                f"{self.file}: node {node.getNamePath()} ({ndname}): its implementation graph "
                f"{graph.getName()} has no output"
            )
        with self.inside(f"node {node.getNamePath()} ({ndname})"):
            p = self.port(out, trail, resolved, True)
        if p is None:
            return None
        return Parameter(
            p.value,
            f"{cat} {node.getNamePath()} ({ndname} via {graph.getName()}) <- {p.provenance}",
            _kind(p),
            p.authored,
        )

    def texture(self, where: Any, ndname: str, resolved: dict[str, Parameter], out_type: str) -> Parameter | None:
        """An ``image`` node: sample its file at its texcoord with OpenImageIO."""
        fp = resolved["file"]
        default = resolved["default"].value
        modes = (resolved["uaddressmode"].value, resolved["vaddressmode"].value)
        uv = np.asarray(resolved["texcoord"].value, dtype=np.float64).reshape(-1)[:2]
        path = fp.value
        space = fp.authored if fp.kind == "file" and fp.authored else "raw"
        label = f"texture {textures.display_name(path) if path else '(none)'} at uv ({uv[0]:.6g}, {uv[1]:.6g})"
        fallback = Parameter(ops._as(default, out_type), f"{label}: default of {where}", "texture")
        if not path:
            self._note(f"image node {where} has no file; its default is used")
            return fallback
        try:
            for mode in modes:
                textures.wrap_name(mode)
            outside = [m == "constant" and not 0.0 <= c <= 1.0 for m, c in zip(modes, uv)]
            if any(outside):
                return Parameter(
                    fallback.value, f"{label}: outside [0, 1] with address mode constant: default of {where}", "texture"
                )
            texel = textures.sample(path, uv, modes[0], modes[1])
        except textures.TextureError as exc:
            self._note(f"{where}: {exc}; the node's default is used")
            return fallback
        except ValueError as exc:
            raise ValueError(f"{self.file}: {where}: {exc}") from None
        value = _channels(texel, out_type)
        value = convert_color(value, out_type, space) if out_type in _COLORS else value
        cs = "" if space in ("raw", colorspace.WORKING_SPACE) else f", {space} -> {colorspace.WORKING_SPACE}"
        return Parameter(
            value,
            f"{label}, wrap {modes[0]}/{modes[1]}{cs} ({path})",
            "texture",
            authored=to_python(_channels(texel, out_type)),
        )


def check_finite(file: str, where: str, p: Parameter) -> None:
    """ValueError when a resolved input's value is not finite (an undefined operation upstream:
    ln of 0, sqrt of a negative number, ...), naming the input and its provenance.

    Examples
    --------
    >>> check_finite("x.mtlx", "S/base_weight", Parameter(0.5, "authored", "authored"))
    >>> check_finite("x.mtlx", "S/base_weight", Parameter(float("nan"), "ln l", "connection"))
    Traceback (most recent call last):
    ...
    ValueError: x.mtlx: S/base_weight: the value is not finite (nan): ln l
    """
    if p.kind != "default" and not ops.finite(p.value):  # defaults: the data library's, finite
        raise ValueError(f"{file}: {where}: the value is not finite ({p.value!r}): {_short(p.provenance)}")


def _array(v):
    """Tuples of floats as float64 arrays (the evaluator's vectors); other values unchanged."""
    return np.asarray(v, dtype=np.float64) if isinstance(v, tuple) else v


def _channels(texel, out_type):
    """Texel channels -> the node's output type (grey replicated, alpha 1 if missing)."""
    n = texel.size
    if out_type == "float":
        return float(texel[0])
    want = int(out_type[-1])
    if n == 1:
        base = np.repeat(texel, min(want, 3))
    else:
        base = texel[: min(n, want)]
    if base.size < want:
        pad = np.ones(want - base.size) if out_type.startswith("color") else np.zeros(want - base.size)
        base = np.concatenate([base, pad])
    return base


def _kind(p):
    return "texture" if p.kind == "texture" else ("file" if p.kind == "file" else "connection")


def _combined(resolved):
    return "texture" if any(p.kind == "texture" for p in resolved.values()) else "connection"


#: Longest provenance kept per input of a node: a graph that reads a node many times would
#: otherwise build provenance strings exponentially long.
PROVENANCE_LIMIT = 400


def _short(text: str, limit: int = PROVENANCE_LIMIT) -> str:
    """``text`` cut to ``limit`` characters (the cut said)."""
    return text if len(text) <= limit else text[:limit] + f"... ({len(text) - limit} more characters)"


def _describe(head: str, resolved: dict) -> str:
    set_ = [f"{n}: {_short(p.provenance)}" for n, p in resolved.items() if p.kind not in ("default",)]
    return f"{head}({'; '.join(set_)})" if set_ else head


__all__ = ["MAX_CHAIN", "deep_stack", "follow", "Resolver", "to_python", "convert_color", "check_finite", "VALUE_TYPES"]
