"""MaterialX documents (.mtlx) read with the MaterialX package.

Materials are the ``surfacematerial`` nodes (their ``surfaceshader`` followed through
nodegraph outputs); a document without material nodes gives one material per unconnected
shader or BSDF node (e.g. a bare ``oren_nayar_diffuse_bsdf``).  Inputs are resolved by the
graph evaluator (``graph.Resolver``) and mapped onto the library's nodes (``mapping``).
The file is only read.
"""
import os

from . import mxlib
from .graph import Resolver, deep_stack, to_python
from .mapping import build_material
from .material import Parameter, failed_material

# ----------------------------------------------------------------------- documents
def read_document(path):
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
SHADER_CATEGORIES = ("open_pbr_surface", "standard_surface", "UsdPreviewSurface", "gltf_pbr",
                     "oren_nayar_diffuse_bsdf", "surface")


def shader_of(node):
    """The shader node a material node uses (following a nodegraph output), or None."""
    inp = node.getInput("surfaceshader")
    return inp.getConnectedNode() if inp is not None else None


def id_of(node) -> str:
    """A node's identity within its document (its name path)."""
    return node.getNamePath()


def graph_shaders(doc, known: set) -> list:
    """[(name, path, shader node)] of the surface shaders that are outputs of nodegraphs
    (e.g. a ``surface`` over an ``oren_nayar_diffuse_bsdf``), as MaterialX's own
    ``findRenderableElements`` finds them; shaders in ``known`` (reached through a material
    node) are left out.  Named by the output's path ("graph/out1")."""
    import MaterialX as mx

    try:
        from MaterialX import PyMaterialXGenShader as gen

        elements = gen.findRenderableElements(doc)
    except Exception:  # an old MaterialX without the helper: the nodegraph outputs themselves
        elements = [o for g in doc.getNodeGraphs() if not g.hasNodeDefString() for o in g.getOutputs()]
    out = []
    for e in elements:
        if not e.isA(mx.Output) or e.getType() != "surfaceshader":
            continue
        node = e.getConnectedNode()
        if node is None or id_of(node) in known:
            continue
        known.add(id_of(node))
        out.append((e.getNamePath(), e.getNamePath(), node))
    return out


def load(path: "str | os.PathLike", *, uv: tuple = (0.5, 0.5), material: str | None = None,
         path_prefix: str | None = None, variants: dict | None = None) -> list:
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
    file = os.fspath(path)
    doc_space = doc.getColorSpace()
    pairs = [(m.getName(), m.getNamePath(), shader_of(m)) for m in doc.getMaterialNodes()]
    if not pairs:  # bare shaders or BSDFs without a material node
        used = set()
        for n in doc.getNodes():
            for i in n.getInputs():
                if i.getNodeName():
                    used.add(i.getNodeName())
        pairs = [(n.getName(), n.getNamePath(), n) for n in doc.getNodes()
                 if n.getCategory() in SHADER_CATEGORIES and n.getName() not in used]
    pairs += graph_shaders(doc, {id_of(sh) for _, _, sh in pairs if sh is not None})
    out = []
    for name, npath, shader in pairs:
        full = f"{path_prefix.rstrip('/')}/{name}" if path_prefix else npath
        if material is not None and material not in (name, npath, full):
            continue
        try:
            with deep_stack():
                m = build_material(_MxShader(shader, file, doc_space), name=name, path=full, file=file, uv=uv,
                                   variants=variants)
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
                    raise ValueError(f"{self.file}: {inp.getNamePath()}: type {inp.getType()}, but input "
                                     f"{name} of {sid} is {t}")
                p = ev.port(inp)
            if p is None:
                if geomprop:
                    continue
                p = Parameter(default, f"default of {sid}", "default")
            params[name] = p if p.kind == "default" else Parameter(to_python(p.value), p.provenance, p.kind,
                                                                    to_python(p.authored))
        return params


__all__ = ["read_document", "load", "SHADER_CATEGORIES"]
