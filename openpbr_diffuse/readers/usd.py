"""USD stages (.usda / .usdc / .usdz) read with usd-core's UsdShade.

Resolution as USD defines it:

- the stage is opened read-only in spirit: variant selections (``variants``) go to the
  session layer, nothing is ever saved, so the file is never modified;
- materials are the ``UsdShade.Material`` prims (also under ``over`` ancestors, as in layers
  meant to be sublayered); the surface shader comes from ``ComputeSurfaceSource("mtlx")``,
  falling back to the universal ``outputs:surface``;
- an input's value follows its connection (``GetConnectedSources``): to a Material or
  NodeGraph interface input, through NodeGraph outputs, to a shader output (whatever its
  name) -- ``UsdUVTexture`` (sampled with OpenImageIO at ``uv``, wrapS/wrapT, scale, bias,
  fallback, sourceColorSpace; a texture inside a ``.usdz`` is read through usd-core's asset
  resolver), ``UsdPrimvarReader_float2`` (the uv), other primvar readers (their fallback, with
  a warning naming the primvar: no geometry is read), ``UsdTransform2d`` and MaterialX ``ND_``
  nodes (evaluated like the MaterialX reader: stdlib math, constant, image, tiledimage);
  else the authored value at ``time`` (an input with only time samples and no ``time``
  given takes its earliest sample); else the MaterialX nodedef default (usd-core has no
  registry for ``ND_`` nodes);
- colour spaces: the attribute's ``colorSpace`` metadata, else ``ColorSpaceAPI`` on the prim
  or its ancestors, else the shader family's default (OpenPBR: ACEScg; Standard Surface and
  UsdPreviewSurface: lin_rec709, USD's default), converted to ACEScg;
- references to ``.mtlx`` documents (which the usd-core wheel cannot compose: "Cannot
  determine file format") are found in the prim stacks and read with the MaterialX reader;
  their materials get the prim paths the MaterialX file-format plugin would give them
  (``<referencing prim>/<material name>`` for ``</MaterialX/Materials>``);
- ``material=`` a geometry prim: its bound material (``ComputeBoundMaterial(purpose)``; a
  binding to a material read from a .mtlx reference is matched by path).
"""

from __future__ import annotations

import os
import struct
from typing import Any

import numpy as np

from . import colorspace, mxlib, ops, package, textures
from ._capture import captured_stderr
from .graph import Resolver, _short, check_finite, convert_color, deep_stack, follow, to_python
from .mapping import build_material
from .material import Material, Parameter, failed_material

_MX_TYPES = {
    "color3f": "color3",
    "color3d": "color3",
    "color3h": "color3",
    "color4f": "color4",
    "color4d": "color4",
    "float": "float",
    "double": "float",
    "half": "float",
    "bool": "boolean",
    "int": "integer",
    "float2": "vector2",
    "texCoord2f": "vector2",
    "double2": "vector2",
    "float3": "vector3",
    "vector3f": "vector3",
    "normal3f": "vector3",
    "point3f": "vector3",
    "float4": "vector4",
    "string": "string",
    "token": "string",
    "asset": "filename",
}


#: Components of the value types (None: not a number).
_SIZES = {"float": 1, "integer": 1, "boolean": 1, "color3": 3, "color4": 4, "vector2": 2, "vector3": 3, "vector4": 4}
#: (components, a colour wanted) -> the type a value of that many components is taken for.
_TYPE_OF_SIZE = {
    (1, False): "float",
    (1, True): "float",
    (2, False): "vector2",
    (2, True): "vector2",
    (3, False): "vector3",
    (3, True): "color3",
    (4, False): "vector4",
    (4, True): "color4",
}


#: Deepest nesting of braces (prims, dictionaries) a text layer may have: usd-core recurses per
#: level and crashes the process (segmentation fault) on ~10^5 nested prims; real assets nest
#: a few tens of levels.
MAX_NESTING = 1000


def _nesting(path):
    """The deepest brace nesting of a text (usda) layer, 0 for a binary one (cheap: one pass)."""
    import numpy as np

    with open(path, "rb") as f:
        head = f.read(6)
        if head != b"#usda ":
            return 0
        data = np.frombuffer(head + f.read(), dtype=np.uint8)
    step = (data == ord("{")).astype(np.int32) - (data == ord("}"))
    return int(np.max(np.cumsum(step), initial=0))


def open_stage(
    path: str | os.PathLike[str],
    diagnostics: list[str],
    *,
    variants: dict[str, str] | None = None,
    time: float | None = None,
) -> Any:
    """Open a stage (ValueError with one line if it cannot be read).

    A text layer nested deeper than :data:`MAX_NESTING` levels is refused before usd-core
    sees it (usd-core would crash the process on it); a stage that could need more memory
    than ``guard.STAGE_BUDGET_MB`` is opened first in a child process under that limit
    (``guard.check_stage``, with the ``variants`` and ``time`` the reader will use).
    """
    from pxr import Tf, Usd

    from . import guard

    depth = _nesting(path)
    if depth > MAX_NESTING:
        raise ValueError(
            f"{path}: nested {depth} levels deep, more than the {MAX_NESTING} this reader "
            f"accepts (usd-core cannot open such a layer safely)"
        )
    guard.check_stage(os.fspath(path), variants, time)

    try:
        with captured_stderr(diagnostics):
            stage = Usd.Stage.Open(os.fspath(path), Usd.Stage.LoadAll)
    except Tf.ErrorException as exc:
        msg = " ".join(_error_text(exc, path).split())
        raise ValueError(f"{path}: not a readable USD stage ({msg[:300]})") from None
    if stage is None:
        raise ValueError(f"{path}: not a readable USD stage")
    return stage


def _error_text(exc: BaseException, path: str | os.PathLike[str]) -> str:
    """usd-core's message, or when it quotes bytes that are not UTF-8 (Python then cannot
    even make it a string) where the layer stops being UTF-8 text."""
    try:
        return str(exc)
    except UnicodeDecodeError:
        pass
    where = _not_utf8(path)
    return f"not UTF-8 text: {where}" if where else "a layer it composes is not UTF-8 text"


def _not_utf8(path: str | os.PathLike[str]) -> str:
    """ "byte 0xe9 at line 2, column 11 (byte 20)" for the first byte of a text layer that is
    not UTF-8 ("" for a binary layer or valid text); reads the file in pieces."""
    line, col, offset, pending = 1, 1, 0, b""

    def advance(text: str) -> None:
        nonlocal line, col
        if "\n" in text:
            line += text.count("\n")
            col = len(text) - text.rfind("\n")
        else:
            col += len(text)

    with open(path, "rb") as f:
        if f.read(6) != b"#usda ":
            return ""
        f.seek(0)
        while True:
            chunk = f.read(1 << 16)
            data = pending + chunk
            try:
                text, pending = data.decode("utf-8"), b""
            except UnicodeDecodeError as exc:
                if exc.reason != "unexpected end of data" or not chunk:
                    advance(data[: exc.start].decode("utf-8"))
                    return f"byte 0x{data[exc.start]:02x} at line {line}, column {col} (byte {offset + exc.start})"
                text, pending = data[: exc.start].decode("utf-8"), data[exc.start :]  # a character cut in two
            advance(text)
            offset += len(data) - len(pending)
            if not chunk:
                return ""


def apply_variants(stage: Any, variants: dict[str, str] | None, diagnostics: list[str]) -> None:
    """Select variants in the session layer; unknown sets / values raise ValueError."""
    from pxr import Usd

    if not variants:
        return
    stage.SetEditTarget(Usd.EditTarget(stage.GetSessionLayer()))
    pending = dict(variants)
    seen_sets: dict[str, set[str]] = {}
    for _ in range(len(pending) + 2):
        progressed = False
        for prim in stage.TraverseAll():
            vsets = prim.GetVariantSets()
            for name in vsets.GetNames():
                seen_sets.setdefault(name, set()).update(vsets.GetVariantSet(name).GetVariantNames())
                if name in pending:
                    vs = vsets.GetVariantSet(name)
                    want = pending[name]
                    if want not in vs.GetVariantNames():
                        raise ValueError(
                            f"variant {name}={want}: no such variant on {prim.GetPath()}; "
                            f"variants of {name}: {', '.join(vs.GetVariantNames())}"
                        )
                    if vs.GetVariantSelection() != want:
                        with captured_stderr(diagnostics):
                            vs.SetVariantSelection(want)
                        progressed = True
        if not progressed:
            break
    missing = [k for k in pending if k not in seen_sets]
    if missing:
        known = ", ".join(sorted(seen_sets)) or "none"
        raise ValueError(f"variant set {missing[0]!r} is not on any prim; variant sets: {known}")


_PXR: dict[str, Any] = {}
_F32 = struct.Struct("f")


def _pxr():
    """(Usd, UsdShade, Sdf), imported once (an import statement per call costs ~30 us)."""
    if not _PXR:
        from pxr import Sdf, Usd, UsdShade

        _PXR.update(Usd=Usd, UsdShade=UsdShade, Sdf=Sdf)
    return _PXR["Usd"], _PXR["UsdShade"], _PXR["Sdf"]


def _py(v):
    """A USD value -> Python (tuples for vectors, str for tokens / asset paths)."""
    _, _, Sdf = _pxr()
    if isinstance(v, Sdf.AssetPath):
        return v
    if hasattr(v, "__len__") and not isinstance(v, str):
        return tuple(map(_f32, v))
    if isinstance(v, bool) or isinstance(v, int):
        return v
    if isinstance(v, float):
        return _f32(v)
    return v


def _f32(x):
    """A float as written: USD hands float32 values over as doubles (0.132 -> 0.13199999928);
    the shortest decimal (7 to 9 digits) that rounds to the same float32 gives back the
    authored text.  Doubles that are not float32 values pass through."""
    x = float(x)
    try:
        if _F32.unpack(_F32.pack(x))[0] != x:
            return x
    except OverflowError:
        return x
    for digits in ("%.7g", "%.8g"):
        y = float(digits % x)
        if _F32.unpack(_F32.pack(y))[0] == x:
            return y
    return float(f"{x:.9g}")


class _UsdResolver:
    """Resolves UsdShade inputs of one material at one time and uv."""

    def __init__(self, file, time, uv, default_space, sink, space_cache=None):
        from pxr import Usd

        self.space_cache = {} if space_cache is None else space_cache
        self.file = str(file)
        self.time = time
        self.tc = Usd.TimeCode(time) if time is not None else Usd.TimeCode.Default()
        self.uv = np.asarray(uv, dtype=np.float64)
        self.default_space = default_space
        self.sink = sink
        self._mx = None
        self._memo = {}  # (shader path, output, type) -> Parameter: each shader output evaluated once

    @property
    def mx(self):
        """The MaterialX graph evaluator (for ND_ nodes and images), made when first needed."""
        if self._mx is None:
            self._mx = Resolver(self.file, self.uv, self.default_space, self.sink)
        return self._mx

    def _note(self, text, unsupported=False):
        lst = self.sink.unsupported if unsupported else self.sink.warnings
        if text not in lst:
            lst.append(text)

    def prim_space(self, prim):
        """ColorSpaceAPI colour space of a prim or its nearest ancestor ('' if none); cached
        per prim path for the whole stage."""
        Usd, _, _ = _pxr()

        key = prim.GetPath()
        if key in self.space_cache:
            return self.space_cache[key]
        if not prim or not prim.IsValid() or prim.IsPseudoRoot():
            name = ""
        elif prim.HasAPI(Usd.ColorSpaceAPI):
            name = Usd.ColorSpaceAPI(prim).GetColorSpaceNameAttr().Get() or ""
        else:
            name = self.prim_space(prim.GetParent())
        self.space_cache[key] = name
        return name

    def space_of(self, attr):
        """Colour space of an attribute: its metadata, else ColorSpaceAPI up the namespace."""
        name = attr.GetColorSpace() if attr.HasColorSpace() else ""
        name = name or self.prim_space(attr.GetPrim()) or self.default_space
        try:
            return colorspace.canonical(name)
        except ValueError as exc:
            raise ValueError(f"{self.file}: {attr.GetPath()}: {exc}") from None

    # ----------------------------------------------------------------- values
    def attr_value(self, attr, mx_type):
        """(value, time note) of an attribute at the resolver's time, or (None, "")."""
        Usd, _, _ = _pxr()

        note = ""
        if self.time is None:
            v = attr.Get()
            if v is None and attr.GetNumTimeSamples() > 0:
                t0 = attr.GetTimeSamples()[0]
                v = attr.Get(Usd.TimeCode(t0))
                note = f" (time samples only, no --time: earliest sample, time {t0:g})"
        else:
            v = attr.Get(self.tc)
            if attr.GetNumTimeSamples() > 0:
                note = f" at time {self.time:g}"
        if v is None:
            return None, ""
        v = _py(v)
        if mx_type == "filename":
            _, _, Sdf = _pxr()
            if isinstance(v, Sdf.AssetPath):
                v = v.resolvedPath or _anchored(attr, v.path)
        return v, note

    def port(self, port, mx_type, trail=()):
        """Resolve a UsdShade Input/Output; None when nothing is authored (use the default)."""
        _, UsdShade, _ = _pxr()

        attr = port.GetAttr()
        trail = follow(self.file, trail, attr.GetPath(), "network", "shaders")
        # most inputs hold a plain value: ask for connection sources only if any are authored
        sources, invalid = port.GetConnectedSources() if attr.HasAuthoredConnections() else ((), ())
        if sources:
            s = sources[0]
            src_prim = s.source.GetPrim()
            if s.sourceType == UsdShade.AttributeType.Output and src_prim.IsA(UsdShade.Shader):
                p = self.shader_value(UsdShade.Shader(src_prim), s.sourceName, mx_type, trail)
                if p is not None:
                    p = self._as_type(p, mx_type, s.source.GetOutput(s.sourceName), attr)
                return p and Parameter(p.value, f"{attr.GetPath()} <- {p.provenance}", _kind(p), p.authored)
            nxt = (
                s.source.GetOutput(s.sourceName)
                if s.sourceType == UsdShade.AttributeType.Output
                else s.source.GetInput(s.sourceName)
            )
            if not nxt:
                self._note(f"{attr.GetPath()}: connected to a missing {s.sourceName!r}; default used")
                return None
            p = self.port(nxt, mx_type, trail)
            if p is None:
                return None
            if s.sourceType == UsdShade.AttributeType.Output:
                return p
            return Parameter(p.value, f"interface {p.provenance}", _kind(p), p.authored)
        if invalid:
            self._note(f"{attr.GetPath()}: connected to {invalid[0]}, which does not exist; default used")
            return None
        v, note = self.attr_value(attr, mx_type)
        if v is None:
            return None
        prov = f"authored at {attr.GetPath()}{note}"
        if mx_type in ("color3", "color4"):
            space = self.space_of(attr)
            value = convert_color(v, mx_type, space)
            if space != colorspace.WORKING_SPACE:
                prov += f" ({space} -> {colorspace.WORKING_SPACE})"
            return Parameter(value, prov, "time" if note else "authored", authored=v)
        if mx_type == "filename":
            return Parameter(v, prov, "file", authored=self.space_of(attr))
        if isinstance(v, tuple):
            v = np.asarray(v, dtype=np.float64)
        return Parameter(v, prov, "time" if note else "authored")

    def _as_type(self, p: Parameter, mx_type: str, output: Any, attr: Any) -> Parameter:
        """A shader output's value connected to an input of ``mx_type``: converted as
        MaterialX's ``ND_convert_<src>_<type>`` converts it when it has another number of
        components (a 2-component uv on a colour input), with a warning; ValueError naming
        the input when MaterialX has no such conversion."""
        want = _SIZES.get(mx_type)
        if want is None or isinstance(p.value, (str, bool)):
            return p
        got = np.asarray(p.value).size
        if got == want:
            return p
        declared = _MX_TYPES.get(str(output.GetTypeName()), "") if output else ""
        src = declared if _SIZES.get(declared) == got else _TYPE_OF_SIZE.get((got, mx_type.startswith("color")), "")
        if not src:
            raise ValueError(f"{self.file}: {attr.GetPath()} ({mx_type}) is connected to a value of {got} components")
        self._note(
            f"{attr.GetPath()} ({mx_type}) is connected to {output.GetAttr().GetPath() if output else 'a value'}, "
            f"a {src} output: the value is converted by MaterialX's ND_convert_{src}_{mx_type}"
        )
        return self.mx.convert(p, src, mx_type, str(attr.GetPath()))

    def inputs(self, shader: Any, sid: str, trail: tuple, authored: dict | None = None) -> dict:
        """Resolved {name: Parameter} of every nodedef input of a shader (defaults filled).

        ``authored``: {name: UsdShade.Input} of the shader's authored inputs (from
        ``GetInputs``, computed here if not given): only those are resolved, the rest take
        the nodedef default without asking USD again.
        """
        if authored is None:
            authored = {i.GetBaseName(): i for i in shader.GetInputs()}
        defs = mxlib.inputs(sid)
        out = dict(mxlib.default_parameters(sid))
        for name, (_t, _default, geomprop) in defs.items():
            if geomprop in ("UV0", "UV1") and name not in authored:
                out[name] = Parameter(self.uv.copy(), f"uv ({self.uv[0]:g}, {self.uv[1]:g})", "uv")
        for name, inp in authored.items():
            if name not in defs:
                continue
            t = defs[name][0]
            tn = str(inp.GetTypeName())
            got = _MX_TYPES.get(tn, tn)
            # float3 / float4 colours: how Blender and the glTF converters write them
            as_colour = t in ("color3", "color4") and got == "vector" + t[-1]
            # a connected input takes its source's value: its own declared type does not matter
            # (exporters write connected inputs as token)
            connected = inp.GetAttr().HasAuthoredConnections()
            if got != t and not as_colour and not connected and not (t == "string" and got == "filename"):
                raise ValueError(f"{self.file}: {inp.GetAttr().GetPath()}: type {tn}, but input {name} of {sid} is {t}")
            p = self.port(inp, t, trail)
            if p is not None:
                out[name] = p
            elif defs[name][2] in ("UV0", "UV1"):
                # connected to something not evaluated (e.g. a texcoord node): the uv point
                out[name] = Parameter(self.uv.copy(), f"uv ({self.uv[0]:g}, {self.uv[1]:g})", "uv")
        # geometry inputs (normals, ...) that nothing supplies are left out
        return {n: out[n] for n in defs if n in out}

    # ----------------------------------------------------------------- shader nodes
    def shader_value(self, shader: Any, output: str, mx_type: str, trail: tuple) -> Parameter | None:
        """The value of ``output`` of a shader prim (memoised per shader, output and type)."""
        key = (shader.GetPath(), output, mx_type)
        if key in self._memo:
            return self._memo[key]
        p = self._shader_value(shader, output, mx_type, trail)
        self._memo[key] = p
        return p

    def _shader_value(self, shader: Any, output: str, mx_type: str, trail: tuple) -> Parameter | None:
        sid = shader.GetShaderId() or ""
        path = str(shader.GetPath())
        trail = follow(self.file, trail, shader.GetPath(), "network", "shaders")
        if sid.startswith("UsdUVTexture"):
            return self.uv_texture(shader, sid, output, mx_type, trail)
        if sid.startswith("UsdPrimvarReader"):
            if sid.endswith("float2") or output == "result" and mx_type == "vector2":
                return Parameter(self.uv.copy(), f"{path} (primvar reader) = uv ({self.uv[0]:g}, {self.uv[1]:g})", "uv")
            return self.primvar_fallback(shader, sid, trail)
        sid = _USD_NODES.get(sid, sid)
        nd = mxlib.nodedef(sid) if sid.startswith("ND_") else None
        if nd is None:
            self._note(f"{path} ({sid or 'no info:id'}) is not evaluated by the reader; default used", True)
            return None
        cat = nd.getNodeString()
        if cat == "texcoord" and nd.getType() == "vector2":
            return Parameter(self.uv.copy(), f"{path} (texcoord) = uv ({self.uv[0]:g}, {self.uv[1]:g})", "uv")
        outs = mxlib.outputs(sid)
        out_type = outs.get(output) or next(iter(outs.values()))
        graph = mxlib.implementation_graph(sid)
        if cat not in ops.OPS and cat != "image" and graph is None:
            self._note(f"{path} ({sid}) is not evaluated by the reader; default used", True)
            return None
        if out_type not in ("float", "color3", "color4", "vector2", "vector3", "vector4", "integer", "boolean"):
            self._note(f"{path} ({sid}) outputs a {out_type}: not a value", True)
            return None
        resolved = self.inputs(shader, sid, trail)
        if cat == "image":
            return self.mx.texture(path, sid, resolved, out_type)
        if graph is None:  # a natively implemented stdlib node (its library graph, if any, defines it)
            try:
                value = ops.apply(cat, {n: p.value for n, p in resolved.items()}, out_type)
            except (TypeError, ValueError, IndexError, KeyError, ArithmeticError) as exc:
                raise ValueError(f"{self.file}: {path} ({sid}): {exc}") from None
            set_ = [f"{n}: {_short(p.provenance)}" for n, p in resolved.items() if p.kind != "default"]
            kind = "texture" if any(p.kind == "texture" for p in resolved.values()) else "connection"
            return Parameter(value, f"{cat} {path}({'; '.join(set_)})", kind)
        out = graph.getOutput(output) or (graph.getOutputs() or [None])[0]
        if out is None:
            raise ValueError(f"{self.file}: {path} ({sid}): its implementation graph {graph.getName()} has no output")
        with self.mx.inside(f"{path} ({sid})"):
            p = self.mx.port(out, (), resolved, True)
        return p and Parameter(
            p.value, f"{cat} {path} ({sid} via {graph.getName()}) <- {p.provenance}", _kind(p), p.authored
        )

    def primvar_fallback(self, shader: Any, sid: str, trail: tuple) -> Parameter | None:
        """A primvar reader other than the uv one: the reader has no geometry, so the
        reader's ``fallback`` (else its nodedef default) is used, with a warning naming the
        primvar."""
        path = str(shader.GetPath())
        nd_name = _PRIMVAR_READERS.get(sid)
        if nd_name is None:
            self._note(f"{path} ({sid}) is not a primvar reader the reader knows; default used", True)
            return None
        var = shader.GetInput("varname")
        v = self.port(var, "string", trail) if var else None
        name = v.value if v is not None else ""
        t, default, _ = mxlib.inputs(nd_name)["fallback"]
        fb = shader.GetInput("fallback")
        p = self.port(fb, t, trail) if fb else None
        value = p.value if p is not None else default
        shown = _fmt4(value) if isinstance(value, (tuple, np.ndarray)) else f"{value}"
        self._note(f"{path} ({sid}) reads primvar {name!r}: no geometry is read, its fallback {shown} is used")
        return Parameter(value, f"{path} ({sid}) primvar {name!r}: fallback {shown} (no geometry)", "connection")

    def uv_texture(self, shader, sid, output, mx_type, trail):
        """UsdUVTexture: file, st, wrapS/T, fallback, scale, bias, sourceColorSpace."""
        path = str(shader.GetPath())

        def get(name, t, default):
            inp = shader.GetInput(name)
            p = self.port(inp, t, trail) if inp else None
            if p is None:
                return default
            v = p.value
            return v if not isinstance(v, np.ndarray) else v

        file_p = shader.GetInput("file")
        fp = self.port(file_p, "filename", trail) if file_p else None
        file = fp.value if fp is not None else ""
        st = get("st", "vector2", self.uv)
        st = np.asarray(st, dtype=np.float64).reshape(-1)[:2]
        wrap_s = str(get("wrapS", "string", "useMetadata"))
        wrap_t = str(get("wrapT", "string", "useMetadata"))
        # raw values: the UsdUVTexture parameters are data, not colours
        fallback = np.asarray(_raw(shader, "fallback", (0.0, 0.0, 0.0, 1.0), self), dtype=np.float64)
        scale = np.asarray(_raw(shader, "scale", (1.0, 1.0, 1.0, 1.0), self), dtype=np.float64)
        bias = np.asarray(_raw(shader, "bias", (0.0, 0.0, 0.0, 0.0), self), dtype=np.float64)
        source_cs = str(get("sourceColorSpace", "string", "auto"))
        label = f"texture {textures.display_name(file) if file else '(none)'} at uv ({st[0]:.6g}, {st[1]:.6g})"
        try:
            if not file:
                raise textures.TextureError(f"{path} has no file")
            for w in (wrap_s, wrap_t):
                textures.wrap_name(w)
            nch, bits, _ = textures.info(file)
            texel = textures.sample(file, st, wrap_s, wrap_t)
        except textures.TextureError as exc:
            self._note(f"{path}: {exc}; its fallback is used")
            rgba = fallback
            prov = f"{label}: fallback of {path}"
            decoded_space = "raw"
        except ValueError as exc:
            raise ValueError(f"{self.file}: {path}: {exc}") from None
        else:
            if nch == 1:
                rgba = np.array([texel[0], texel[0], texel[0], 1.0])
            elif nch == 2:
                rgba = np.array([texel[0], texel[0], texel[0], texel[1]])
            elif nch == 3:
                rgba = np.array([texel[0], texel[1], texel[2], 1.0])
            else:
                rgba = texel[:4].copy()
            # "auto": sRGB for 8-bit textures of 3 or 4 channels only (UsdPreviewSurface
            # specification; OpenUSD's Hio does the same); 1- and 2-channel ones are data
            srgb = source_cs == "sRGB" or (source_cs == "auto" and bits == 8 and nch in (3, 4))
            if srgb:
                rgba[:3] = _srgb_decode(rgba[:3])
            rgba = rgba * scale + bias
            decoded_space = self.space_of(shader.GetInput("file").GetAttr()) if file_p else self.default_space
            prov = (
                f"{label}, wrap {wrap_s}/{wrap_t}, scale {_fmt4(scale)}, bias {_fmt4(bias)}, "
                f"sourceColorSpace {source_cs}{' (sRGB decoded)' if srgb else ''} ({file})"
            )
        channel = {"r": 0, "g": 1, "b": 2, "a": 3}
        if output in channel:
            return Parameter(float(rgba[channel[output]]), f"{path}.outputs:{output} <- {prov}", "texture")
        if output != "rgb":
            self._note(f"{path}: unknown UsdUVTexture output {output!r}; default used")
            return None
        rgb = rgba[:3]
        if mx_type in ("color3", "color4") and decoded_space != "raw":
            rgb = colorspace.to_working(rgb, decoded_space)
            if decoded_space != colorspace.WORKING_SPACE:
                prov += f" ({decoded_space} -> {colorspace.WORKING_SPACE})"
        return Parameter(
            ops._as(rgb, mx_type) if mx_type != "float" else float(rgb[0]), f"{path}.outputs:rgb <- {prov}", "texture"
        )


#: USD shader ids of UsdPreviewSurface nodes that MaterialX's data library defines (the
#: ``ND_`` nodedef gives the inputs' types and defaults, its nodegraph the evaluation).
_USD_NODES = {"UsdTransform2d": "ND_UsdTransform2d"}

#: Primvar readers (UsdPreviewSurface specification) -> the MaterialX nodedef of their type.
_PRIMVAR_READERS = {
    "UsdPrimvarReader_float": "ND_UsdPrimvarReader_float",
    "UsdPrimvarReader_float3": "ND_UsdPrimvarReader_vector3",
    "UsdPrimvarReader_float4": "ND_UsdPrimvarReader_vector4",
    "UsdPrimvarReader_int": "ND_UsdPrimvarReader_integer",
    "UsdPrimvarReader_string": "ND_UsdPrimvarReader_string",
    "UsdPrimvarReader_normal": "ND_UsdPrimvarReader_vector3",
    "UsdPrimvarReader_point": "ND_UsdPrimvarReader_vector3",
    "UsdPrimvarReader_vector": "ND_UsdPrimvarReader_vector3",
    "UsdPrimvarReader_matrix": None,
}
_PRIMVAR_READERS = {k: v for k, v in _PRIMVAR_READERS.items() if v is not None}


def _anchored(attr: Any, path: str) -> str:
    """An asset path the resolver did not resolve, anchored to the layer that authors it
    (inside a package: the package member ``pkg.usdz[path]``), for the warning to name."""
    from pxr import Ar

    if not path or os.path.isabs(path) or Ar.IsPackageRelativePath(path):
        return path
    stack = attr.GetPropertyStack()
    layer = stack[0].layer if stack else attr.GetStage().GetRootLayer()
    real = layer.realPath or layer.identifier
    if Ar.IsPackageRelativePath(real):  # a layer inside a package: relative to its member folder
        outer, inner = Ar.SplitPackageRelativePathInner(real)
        return Ar.JoinPackageRelativePath([outer, os.path.normpath(os.path.join(os.path.dirname(inner), path))])
    if os.path.splitext(real)[1].lower() == ".usdz":
        return Ar.JoinPackageRelativePath([real, os.path.normpath(path)])
    return os.path.normpath(os.path.join(os.path.dirname(real), path))


def _raw(shader, name, default, res):
    inp = shader.GetInput(name)
    if not inp:
        return default
    v, _ = res.attr_value(inp.GetAttr(), "vector4")
    return default if v is None else v


def _srgb_decode(v):
    return colorspace.decode(v, "srgb_texture")


def _fmt4(a):
    return "(" + ", ".join(f"{x:g}" for x in np.asarray(a).reshape(-1)) + ")"


def _kind(p):
    return p.kind if p.kind in ("texture", "time", "file") else "connection"


def _no_id(shader: Any) -> str:
    """How a shader without ``info:id`` says what it is: its ``info:implementationSource``
    (sourceAsset: the asset of each source type; sourceCode) -- an Sdr shader the readers
    cannot map."""
    if not shader:
        return "(no info:id)"
    source = shader.GetImplementationSource()
    if source == "sourceAsset":
        assets = []
        for attr in shader.GetPrim().GetAttributes():
            name = attr.GetName()
            if name.startswith("info:") and name.endswith(":sourceAsset"):
                v = attr.Get()
                assets.append(f"{name.split(':')[1]} {getattr(v, 'path', v)}")
        return f"(no info:id; implementationSource sourceAsset: {', '.join(assets) or 'no asset'})"
    if source == "sourceCode":
        kinds = sorted(
            a.GetName().split(":")[1]
            for a in shader.GetPrim().GetAttributes()
            if a.GetName().startswith("info:") and a.GetName().endswith(":sourceCode")
        )
        return f"(no info:id; implementationSource sourceCode{': ' + ', '.join(kinds) if kinds else ''})"
    return "(no info:id)"


def _no_surface_reason(mat: Any) -> str:
    """Why a UsdShade material has no surface shader: where its surface outputs lead, or which
    outputs it has instead."""
    from pxr import UsdShade

    said = []
    for out in mat.GetOutputs():
        name = out.GetBaseName()
        targets = out.GetAttr().GetConnections()
        if not name.split(":")[-1] == "surface":
            continue
        for t in targets:
            prim = mat.GetPrim().GetStage().GetPrimAtPath(t.GetPrimPath())
            if not prim:
                said.append(f"outputs:{name} connects to {t}, which does not exist")
            elif not prim.IsA(UsdShade.Shader) and prim != mat.GetPrim():
                said.append(f"outputs:{name} connects to {t}, which is not a shader")
            else:
                said.append(f"outputs:{name} connects to {t}, which is not a surface shader output")
    if not said:
        others = sorted(f"outputs:{o.GetBaseName()}" for o in mat.GetOutputs() if o.GetAttr().GetConnections())
        said.append(f"it has no surface output{' (only ' + ', '.join(others) + ')' if others else ''}")
    return "; ".join(said)


class _UsdShader:
    """Adapter: a UsdShade shader prim as seen by ``mapping.build_material``."""

    def __init__(self, shader, file, time, space_cache=None):
        self.shader = shader
        self.node = shader if shader else None
        self.file = file
        self.time = time
        self.space_cache = space_cache
        self._sid = None

    @property
    def path(self):
        return str(self.shader.GetPath()) if self.shader else ""

    def shader_id(self):
        if self._sid is None:
            sid = self.shader.GetShaderId() if self.shader else ""
            self._sid = sid or _no_id(self.shader)
        return self._sid

    def unwrap_surface(self):
        from pxr import UsdShade

        if self.shader_id() != "ND_surface":
            return None
        inp = self.shader.GetInput("bsdf")
        if not inp:
            return None
        sources, _ = inp.GetConnectedSources()
        if not sources or not sources[0].source.GetPrim().IsA(UsdShade.Shader):
            return None
        return _UsdShader(UsdShade.Shader(sources[0].source.GetPrim()), self.file, self.time, self.space_cache)

    def resolve(self, sid, default_space, sink, uv):
        res = _UsdResolver(self.file, self.time, uv, default_space, sink, self.space_cache)
        defs = mxlib.inputs(sid)
        authored = {i.GetBaseName(): i for i in self.shader.GetInputs()}
        for name, inp in authored.items():
            if name not in defs:
                sink.warnings.append(f"{inp.GetAttr().GetPath()}: not an input of {sid}; ignored")
        params = res.inputs(self.shader, sid, (self.shader.GetPath(),), authored)
        for n, p in params.items():
            check_finite(self.file, f"{self.shader.GetPath()}.inputs:{n}", p)
        return {
            n: p if p.kind == "default" else Parameter(to_python(p.value), p.provenance, p.kind, to_python(p.authored))
            for n, p in params.items()
        }


# ----------------------------------------------------------------------- stage
def _mtlx_references(prim):
    """[(absolute .mtlx path, referenced prim path)] of the references/payloads of ``prim``."""
    out = []
    if not (prim.HasAuthoredReferences() or prim.HasAuthoredPayloads()):
        return out
    for spec in prim.GetPrimStack():
        for lst in (spec.referenceList, spec.payloadList):
            items = list(lst.explicitItems) + list(lst.prependedItems) + list(lst.appendedItems) + list(lst.addedItems)
            for r in items:
                if r.assetPath.lower().endswith(".mtlx"):
                    out.append((spec.layer.ComputeAbsolutePath(r.assetPath), str(r.primPath)))
    seen, uniq = set(), []
    for x in out:
        if x not in seen:
            seen.add(x)
            uniq.append(x)
    return uniq


class _Entry:
    """A material found on the stage, built on demand."""

    def __init__(self, path, name, build):
        self.path, self.name, self.build = path, name, build


def _entries(stage, file, time, uv, variants, diagnostics):
    from pxr import UsdShade

    from . import materialx

    entries = []
    space_cache = {}
    for prim in stage.TraverseAll():
        if prim.IsA(UsdShade.Material):

            def build(prim=prim):
                mat = UsdShade.Material(prim)
                shader, _, _ = mat.ComputeSurfaceSource("mtlx")
                adapter = _UsdShader(shader if shader else None, file, time, space_cache)
                m = build_material(
                    adapter,
                    name=prim.GetName(),
                    path=str(prim.GetPath()),
                    file=file,
                    uv=uv,
                    variants=variants,
                    time=time,
                )
                if not shader and m.unsupported:
                    m.unsupported[0] += f" ({_no_surface_reason(mat)})"
                return m

            entries.append(_Entry(str(prim.GetPath()), prim.GetName(), build))
        for mtlx, target in _mtlx_references(prim):
            prefix = str(prim.GetPath())
            only = None
            parts = [p for p in target.split("/") if p]
            if len(parts) >= 3 and parts[:2] == ["MaterialX", "Materials"]:
                only = parts[2]
                prefix = str(prim.GetPath().GetParentPath())
            elif parts == ["MaterialX"]:
                prefix += "/Materials"
            if not os.path.isfile(mtlx):
                diagnostics.append(f"{prim.GetPath()}: referenced MaterialX document {mtlx} does not exist")
                continue
            names = _mtlx_names(mtlx)
            for name in names:
                if only is not None and name != only:
                    continue
                path = f"{prefix}/{name}" if only is None else str(prim.GetPath())

                def build_referenced(mtlx=mtlx, name=name, path=path, prim_path=str(prim.GetPath())):  # noqa: B008 (bound per prim)
                    got = materialx.load(mtlx, uv=uv, material=name)
                    m = got[0]
                    m.path = path
                    m.variants = dict(variants or {})
                    m.warnings.insert(
                        0,
                        f"read with MaterialX from {mtlx}, referenced by {prim_path} "
                        f"(usd-core cannot compose .mtlx references)",
                    )
                    return m

                entries.append(_Entry(path, name, build_referenced))
    return entries


def _build(entry: _Entry, file: str, uv: tuple, variants: dict | None, time: object) -> Material:
    """Build one material; an error fails that material only (``Material.error``)."""
    try:
        with deep_stack():
            return entry.build()
    except Exception as exc:  # one bad value fails its own material, never the stage
        return failed_material(exc, name=entry.name, path=entry.path, file=file, uv=uv, variants=variants, time=time)


def _mtlx_names(path):
    from .materialx import read_document

    doc = read_document(path)
    names = [m.getName() for m in doc.getMaterialNodes()]
    return names


def _bound(stage, prim, purpose, entries):
    """The entry of the material bound to ``prim`` (None if unbound)."""
    from pxr import UsdShade

    token = {"full": UsdShade.Tokens.full, "preview": UsdShade.Tokens.preview, "": UsdShade.Tokens.allPurpose}[purpose]
    api = UsdShade.MaterialBindingAPI(prim)
    mat, rel = api.ComputeBoundMaterial(token)
    by_path = {e.path: e for e in entries}
    if mat:
        return by_path.get(str(mat.GetPath()))
    # a binding to a material read from a .mtlx reference has no prim on the stage
    for p in (purpose, ""):
        for ancestor in _ancestors(prim):
            b = UsdShade.MaterialBindingAPI(ancestor)
            r = b.GetDirectBindingRel(p if p != "full" else UsdShade.Tokens.full) if p else b.GetDirectBindingRel()
            targets = r.GetTargets() if r else []
            if targets and str(targets[0]) in by_path:
                return by_path[str(targets[0])]
    return None


def _ancestors(prim):
    while prim and not prim.IsPseudoRoot():
        yield prim
        prim = prim.GetParent()


def load(
    path: str | os.PathLike[str],
    *,
    time: float | None = None,
    variants: dict[str, str] | None = None,
    uv: tuple[float, float] = (0.5, 0.5),
    material: str | None = None,
    purpose: str = "full",
) -> list[Material]:
    """Materials of a USD stage (see the module docstring)."""
    import gc

    # reading thousands of materials allocates many small objects that all stay alive: the
    # cyclic garbage collector's passes over them are wasted work (~8 %), so it pauses here
    enabled = gc.isenabled()
    gc.disable()
    try:
        return _load(path, time=time, variants=variants, uv=uv, material=material, purpose=purpose)
    finally:
        if enabled:
            gc.enable()


def _load(
    path: str | os.PathLike[str],
    *,
    time: float | None,
    variants: dict[str, str] | None,
    uv: tuple,
    material: str | None,
    purpose: str,
) -> list[Material]:
    from pxr import Sdf, UsdShade

    file = os.fspath(path)
    if os.path.splitext(file)[1].lower() == ".usdz":
        root = package.members(file)[0]  # checked as usd-core will read it
        if os.path.splitext(root.name)[1].lower() == ".mtlx":
            if variants:
                raise ValueError(f"{file}: variants apply to USD stages; its root document {root.name} is MaterialX")
            from . import materialx

            return materialx.load_packaged(file, root, uv=uv, material=material)
    diagnostics: list[str] = []
    stage = open_stage(file, diagnostics, variants=variants, time=time)
    apply_variants(stage, variants, diagnostics)
    entries = _entries(stage, file, time, uv, variants, diagnostics)
    chosen = entries
    if material is not None:
        chosen = [e for e in entries if material in (e.path, e.name)]
        if not chosen:
            prims = []
            if material.startswith("/") and Sdf.Path.IsValidPathString(material):
                prim = stage.GetPrimAtPath(material)
                prims = [prim] if prim else []
            else:
                prims = [p for p in stage.TraverseAll() if p.GetName() == material]
            if not prims:
                raise ValueError(f"{file}: no material or prim {material!r}")
            for prim in prims:
                e = _bound(stage, prim, purpose, entries)
                if e is None:
                    if prim.IsA(UsdShade.Material):
                        continue
                    raise ValueError(
                        f"{file}: prim {prim.GetPath()} has no bound material (purpose {purpose or 'all'})"
                    )
                chosen.append(e)
    mats = [_build(e, file, uv, variants, time) for e in chosen]
    useful = [d for d in diagnostics if "Cannot determine file format" not in d and ".mtlx" not in d]
    for m in mats:
        m.warnings += [f"USD: {d.strip()[:300]}" for d in useful]
    return mats


__all__ = ["load", "open_stage", "apply_variants", "captured_stderr"]
