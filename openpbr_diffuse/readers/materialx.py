"""MaterialX documents (.mtlx) read with the MaterialX package.

Materials are the ``surfacematerial`` nodes (their ``surfaceshader`` followed through
nodegraph outputs); a document without material nodes gives one material per unconnected
shader or BSDF node (e.g. a bare ``oren_nayar_diffuse_bsdf``).  Inputs are resolved by the
graph evaluator (``graph.Resolver``) and mapped onto the library's nodes (``mapping``).
The file is only read.
"""

from __future__ import annotations

import os
import re
from typing import Any

from . import mxlib
from .graph import Resolver, check_finite, deep_stack, to_python
from .mapping import build_material
from .material import Material, Parameter, failed_material


# ----------------------------------------------------------------------- documents
def read_document(path: str | os.PathLike[str]) -> Any:
    """Read a .mtlx file (never modified) with the MaterialX data library attached.

    Raises FileNotFoundError / ValueError (malformed or unreadable) with one-line messages.
    """
    import MaterialX as mx

    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{path}: no such file")
    doc = mx.createDocument()
    try:
        mx.readFromXmlFile(doc, path)
    except Exception as exc:  # MaterialX raises its own exception types (ExceptionParseError, ...)
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(f"{path}: not a readable MaterialX document ({msg})") from None
    doc.setDataLibrary(mxlib.library())
    return doc


#: Node categories that are surface shaders (or bare BSDFs) the readers look at.
SHADER_CATEGORIES = (
    "open_pbr_surface",
    "standard_surface",
    "UsdPreviewSurface",
    "gltf_pbr",
    "oren_nayar_diffuse_bsdf",
    "surface",
)


def shader_of(node: Any) -> Any:
    """The shader node a material node uses (following a nodegraph output), or None."""
    inp = node.getInput("surfaceshader")
    return inp.getConnectedNode() if inp is not None else None


def id_of(node: Any) -> str:
    """A node's identity within its document (its name path)."""
    return node.getNamePath()


#: The ``unsupported`` reason of a renderable nodegraph output that is not a surface shader.
NOT_A_SHADER = "not a surface shader: MaterialX renders it unlit, there is no diffuse lobe to evaluate"


def graph_shaders(doc: Any, known: set) -> list:
    """[(name, path, shader node or output)] of the renderable nodegraph / document outputs that
    MaterialX's own ``findRenderableElements`` finds: a surface shader output (e.g. a ``surface``
    over an ``oren_nayar_diffuse_bsdf``), a ``material`` output (followed to the shader of its
    ``surfacematerial``), or another output (a colour, a float, a displacement shader: the
    Output itself, listed unsupported).  Named by the output's path ("graph/out1"); a shader in
    ``known`` (reached through a material node), by the same output of the same node, is left out."""
    import MaterialX as mx

    try:
        from MaterialX import PyMaterialXGenShader as gen

        elements = gen.findRenderableElements(doc)
    except Exception:  # an old MaterialX without the helper: the nodegraph outputs themselves
        elements = [o for g in doc.getNodeGraphs() if not g.hasNodeDefString() for o in g.getOutputs()]
    out = []
    for e in elements:
        if not e.isA(mx.Output):
            continue
        node = e.getConnectedNode()
        if e.getType() == "material" and node is not None and node.getType() == "material":
            node = shader_of(node)
            if node is None:  # listed: "no surface shader is connected to the material"
                out.append((e.getNamePath(), e.getNamePath(), None))
                continue
        elif e.getType() != "surfaceshader":
            out.append((e.getNamePath(), e.getNamePath(), e))
            continue
        if node is None or (id_of(node), e.getOutputString()) in known:
            continue
        out.append((e.getNamePath(), e.getNamePath(), node))
    return out


def _not_a_shader(output, *, name, path, file, uv, variants):
    """The Material listed for a renderable output that is not a surface shader."""
    node = output.getConnectedNode()
    nd = node.getNodeDef() if node is not None else None
    return Material(
        name=name,
        path=path,
        file=file,
        shader_id=nd.getName() if nd is not None else "",
        supported=False,
        uv=tuple(float(x) for x in uv),
        variants=dict(variants or {}),
        shader_path=node.getNamePath() if node is not None else "",
        unsupported=[f"{output.getNamePath()}: a {output.getType()} output, {NOT_A_SHADER}"],
    )


def load(
    path: str | os.PathLike,
    *,
    uv: tuple = (0.5, 0.5),
    material: str | None = None,
    path_prefix: str | None = None,
    variants: dict | None = None,
) -> list:
    """Materials of a MaterialX document.

    Parameters
    ----------
    path : str or Path
    uv : (u, v)
        Where textures are sampled.
    material : str, optional
        Keep only the material with this name or node path.
    path_prefix : str, optional
        Prefix of ``Material.path`` (a USD prim path when the document is referenced from a
        USD stage); default: the node name path.

    Returns
    -------
    list of Material
    """
    doc = read_document(path)
    return materials_of(doc, os.fspath(path), uv=uv, material=material, path_prefix=path_prefix, variants=variants)


#: An ``xi:include`` of a document's text and the file it names.
_INCLUDE = re.compile(r"""<xi:include\b[^>]*?\bhref\s*=\s*["']([^"']*)["']""")


def load_packaged(
    package: str | os.PathLike, member: Any, *, uv: tuple = (0.5, 0.5), material: str | None = None
) -> list:
    """Materials of a MaterialX document that is the root (first) member of a ``.usdz``
    package (usd-core opens only USD layers as a package's root).

    The member is read within its size (``package.read_member``); its relative file names
    are members of the same package (``pkg.usdz[textures/a.png]``, read through usd-core's
    asset resolver); its ``xi:include``s are not read (outside the package, MaterialX would
    look them up relative to the working directory), with a warning.  ``Material.file`` is
    the package; messages name the member as ``pkg.usdz[doc.mtlx]``.
    """
    import MaterialX as mx

    from . import package as pkg

    outer = os.fspath(package)
    name = f"{outer}[{member.name}]"
    text = pkg.read_member(outer, member).decode("utf-8", "replace")
    doc = mx.createDocument()
    options = mx.XmlReadOptions()
    options.readXIncludeFunction = None
    try:
        mx.readFromXmlString(doc, text, mx.FileSearchPath(), options)
    except Exception as exc:  # MaterialX raises its own exception types
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(f"{name}: not a readable MaterialX document ({msg})") from None
    doc.setDataLibrary(mxlib.library())
    mats = materials_of(doc, outer, uv=uv, material=material, source=name)
    notes = [f"read with MaterialX from {name}, the package's root document (usd-core opens only USD layers as a root)"]
    notes += [
        f"{name}: xi:include of {href!r} is not read (a document inside a package includes nothing from outside it)"
        for href in _INCLUDE.findall(text)
    ]
    for m in mats:
        m.warnings[:0] = notes
    return mats


def materials_of(
    doc: Any,
    file: str,
    *,
    uv: tuple = (0.5, 0.5),
    material: str | None = None,
    path_prefix: str | None = None,
    variants: dict | None = None,
    source: str | None = None,
) -> list:
    """Materials of a MaterialX document already read (see :func:`load`); ``source``: how
    messages name the document (default ``file``; a package member ``pkg.usdz[doc.mtlx]``,
    whose relative file names are then members of the same package)."""
    import MaterialX as mx

    source = source or file
    doc_space = doc.getColorSpace()
    material_nodes = doc.getMaterialNodes()
    pairs = [(m.getName(), m.getNamePath(), shader_of(m)) for m in material_nodes]
    if not pairs:  # bare shaders or BSDFs without a material node
        used = set()
        for n in doc.getNodes():
            for i in n.getInputs():
                if i.getNodeName():
                    used.add(i.getNodeName())
        pairs = [
            (n.getName(), n.getNamePath(), n)
            for n in doc.getNodes()
            if n.getCategory() in SHADER_CATEGORIES and n.getName() not in used
        ]
    outputs = graph_shaders(doc, {(id_of(sh), "") for _, _, sh in pairs if sh is not None} if material_nodes else set())
    if not material_nodes:  # a bare shader that a renderable output reaches is listed by that output
        reached = {id_of(sh) for _, _, sh in outputs if sh is not None and not sh.isA(mx.Output)}
        pairs = [p for p in pairs if p[2] is None or id_of(p[2]) not in reached]
    pairs += outputs
    out = []
    for name, npath, shader in pairs:
        full = f"{path_prefix.rstrip('/')}/{name}" if path_prefix else npath
        if material is not None and material not in (name, npath, full):
            continue
        if shader is not None and shader.isA(mx.Output):
            out.append(_not_a_shader(shader, name=name, path=full, file=file, uv=uv, variants=variants))
            continue
        try:
            with deep_stack():
                m = build_material(
                    _MxShader(shader, source, doc_space), name=name, path=full, file=file, uv=uv, variants=variants
                )
        except Exception as exc:  # one bad value fails its own material, never the document
            m = failed_material(exc, name=name, path=full, file=file, uv=uv, variants=variants)
        out.append(m)
    return out


class _MxShader:
    """Adapter: a MaterialX shader node as seen by ``mapping.build_material``."""

    def __init__(self, node, file, doc_space):
        self.node = node
        self.file = file
        self.doc_space = doc_space

    @property
    def path(self):
        return self.node.getNamePath() if self.node is not None else ""

    def shader_id(self):
        if self.node is None:
            return ""
        nd = self.node.getNodeDef()
        if nd is None:
            # no exact match (e.g. an input of the wrong type): the library's nodedef of this
            # category and output type, so that resolve() names the offending input
            for cand in mxlib.library().getMatchingNodeDefs(self.node.getCategory()):
                if cand.getType() == self.node.getType() and cand.getNodeString() == self.node.getCategory():
                    return cand.getName()
        return nd.getName() if nd is not None else f"{self.node.getCategory()} ({self.node.getType()}, no nodedef)"

    def unwrap_surface(self):
        """A ``surface`` node whose bsdf is an oren_nayar_diffuse_bsdf -> that BSDF node."""
        if self.node is None or self.node.getCategory() != "surface":
            return None
        bsdf = self.node.getInput("bsdf")
        target = bsdf.getConnectedNode() if bsdf is not None else None
        if target is None:
            return None
        return _MxShader(target, self.file, self.doc_space)

    def resolve(self, sid, default_space, sink, uv):
        """{input name: Parameter} of every nodedef input (defaults from the library)."""
        ev = Resolver(self.file, uv, self.doc_space or default_space, sink)
        params = {}
        defs = mxlib.inputs(sid)
        for name in [i.getName() for i in self.node.getInputs()]:
            if name not in defs:
                sink.warnings.append(f"{self.node.getNamePath()}: input {name!r} is not an input of {sid}; ignored")
        for name, (t, default, geomprop) in defs.items():
            inp = self.node.getInput(name)
            p = None
            if inp is not None:
                if inp.getType() != t:
                    raise ValueError(
                        f"{self.file}: {inp.getNamePath()}: type {inp.getType()}, but input {name} of {sid} is {t}"
                    )
                p = ev.port(inp)
            if p is None:
                if geomprop:
                    continue
                p = Parameter(default, f"default of {sid}", "default")
            check_finite(self.file, inp.getNamePath() if inp is not None else f"{self.node.getNamePath()}.{name}", p)
            params[name] = (
                p if p.kind == "default" else Parameter(to_python(p.value), p.provenance, p.kind, to_python(p.authored))
            )
        return params


__all__ = ["read_document", "load", "load_packaged", "materials_of", "SHADER_CATEGORIES"]
