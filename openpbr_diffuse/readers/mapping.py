"""Which library node a shader maps onto, and how its inputs become the node's inputs.

A table (shader id -> ``Family``), not an if-chain:

- ``ND_open_pbr_surface_surfaceshader`` -> ``OpenPBRSurface`` (diffuse EON), inputs as they are;
- ``ND_standard_surface_surfaceshader`` -> ``OpenPBRSurface(diffuse_model="qon")``: the
  inputs go through MaterialX's own translation graph ``ND_standard_surface_to_open_pbr_surface``
  (evaluated by ``materialx.Resolver``; base_diffuse_roughness = diffuse_roughness, used as
  QON's sigma in radians, as MaterialX's standard_surface graph does);
- ``UsdPreviewSurface`` -> ``OpenPBRSurface(diffuse_model="lambert")``: diffuseColor ->
  base_color, metallic -> base_metalness, roughness -> specular_roughness (it is the specular
  roughness), ior -> specular_ior, clearcoat -> coat_weight, clearcoatRoughness ->
  coat_roughness, opacity -> geometry_opacity;
- ``ND_gltf_pbr_surfaceshader`` -> ``OpenPBRSurface(diffuse_model="lambert")`` (its diffuse is
  MaterialX's oren_nayar_diffuse_bsdf of roughness 0): base_color, metallic -> base_metalness,
  roughness -> specular_roughness, ior, specular / specular_color, transmission, clearcoat ->
  coat (IOR 1.5), sheen -> fuzz, iridescence -> thin film (nm -> um), alpha by alpha_mode ->
  geometry_opacity;
- ``ND_oren_nayar_diffuse_bsdf`` (bare, or as the bsdf of a ``surface`` node) ->
  ``OrenNayarDiffuseBSDF``.

Anything else is ``supported = False`` with its shader id.  Values outside the node's
nodedef range are clamped to it with a warning (OpenPBR's reference graph clamps base_color
with max(base_color, 0) and the scaled specular F0 to [0, 0.99999]; the library's nodes
accept only the nodedef's [uimin, uimax]).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import mxlib
from .material import Material, Parameter, diffuse_model_available, empty_material

OPENPBR = "ND_open_pbr_surface_surfaceshader"
STANDARD_SURFACE = "ND_standard_surface_surfaceshader"
PREVIEW = "ND_UsdPreviewSurface_surfaceshader"
OREN_NAYAR = "ND_oren_nayar_diffuse_bsdf"
GLTF_PBR = "ND_gltf_pbr_surfaceshader"
TRANSLATION = "ND_standard_surface_to_open_pbr_surface"

#: Shader ids written in USD files that name the same nodedefs.
ALIASES = {"UsdPreviewSurface": PREVIEW, "ND_standard_surface_surfaceshader_100": STANDARD_SURFACE}


@dataclass(frozen=True)
class Family:
    node_class: str
    diffuse_model: str
    default_space: str
    map: Callable


@functools.lru_cache(maxsize=1)
def _modelled():
    from ..nodes import openpbr_surface

    return frozenset(getattr(openpbr_surface, "MODELLED", ()))


def _differs(value, default):
    """True if a resolved value is not the nodedef default (exact comparison)."""
    if isinstance(value, np.ndarray):
        value = tuple(float(x) for x in value.reshape(-1))
    return value != default


def _fmt(v):
    if isinstance(v, tuple):
        return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


#: An OpenPBR lobe's inputs matter only when its weight is non-zero (prefix -> weight input).
_GATES = {
    "coat_": "coat_weight",
    "fuzz_": "fuzz_weight",
    "subsurface_": "subsurface_weight",
    "transmission_": "transmission_weight",
    "thin_film_": "thin_film_weight",
    "emission_": "emission_luminance",
}


def _gated_off(name, inputs):
    for prefix, weight in _GATES.items():
        if name.startswith(prefix) and name != weight and weight in inputs:
            return inputs[weight].value == 0
    return False


def _openpbr_inputs(inputs, m):
    """Keep the OpenPBR inputs (no geometry props); list the set-but-unmodelled ones (a
    lobe's colour, roughness, ... only when its weight is non-zero)."""
    modelled = _modelled()
    defs = mxlib.inputs(OPENPBR)
    defaults = mxlib.default_parameters(OPENPBR)
    if inputs.keys() >= defaults.keys():
        out = {n: inputs[n] for n in defaults}
    else:  # a mapped shader without some inputs: OpenPBR's defaults
        prov = f"default of {OPENPBR} (no counterpart in {m.shader_id})"
        out = {n: inputs[n] if n in inputs else Parameter(p.value, prov, "default") for n, p in defaults.items()}
    for name, p in out.items():
        if p.kind == "default" or name in modelled:
            continue
        if _differs(p.value, defs[name][1]) and not _gated_off(name, out):
            m.unsupported.append(f"{name} = {_fmt(p.value)} (not modelled by OpenPBRSurface)")
    return out


def _to_openpbr(m, mapped, nodedef, unmodelled, why, approximations):
    """The OpenPBR inputs of a shader of ``nodedef`` whose inputs were ``mapped`` onto OpenPBR's:
    the inputs of ``unmodelled`` whose value is not ``nodedef``'s default are listed as
    unsupported (``why``), the mapping's ``approximations`` are noted."""
    defaults = mxlib.inputs(nodedef)
    for name in unmodelled:
        value = m.parameters[name].value
        if _differs(value, defaults[name][1]):
            m.unsupported.append(f"{name} = {_fmt(value)} ({why})")
    m.approximations += approximations
    return _openpbr_inputs(mapped, m)


def _renamed(parameters, names, shader):
    """The ``parameters`` of ``names`` (source -> OpenPBR input) under their OpenPBR names."""
    out = {}
    for src, dst in names.items():
        p = parameters[src]
        out[dst] = Parameter(p.value, f"{shader} {src} -> {dst}: {p.provenance}", "mapped", p.authored)
    return out


def _map_openpbr(m):
    return _openpbr_inputs(m.parameters, m)


@functools.lru_cache(maxsize=1)
def _translation_dependencies():
    """{output name: the interface inputs it depends on} of the translation graph (static)."""
    graph = mxlib.implementation_graph(TRANSLATION)

    def deps(port, seen):
        if port.hasInterfaceName():
            return {port.getInterfaceName()}
        node = port.getConnectedNode()
        if node is None or node.getNamePath() in seen:
            return set()
        seen = seen | {node.getNamePath()}
        out = set()
        for i in node.getInputs():
            out |= deps(i, seen)
        return out

    return {o.getName(): deps(o, frozenset()) for o in graph.getOutputs()}


def _translate(outputs, params, m):
    """Evaluate ``outputs`` of the translation graph with the Standard Surface ``params``."""
    from .graph import Resolver, to_python

    graph = mxlib.implementation_graph(TRANSLATION)
    iface = {
        n: Parameter(
            np.asarray(p.value, dtype=np.float64) if isinstance(p.value, tuple) else p.value, p.provenance, p.kind
        )
        for n, p in params.items()
    }
    ev = Resolver(
        m.file if m is not None else "", (0.5, 0.5), "raw", m if m is not None else Material("", "", "", "", False)
    )
    out = {}
    for name in outputs:
        p = ev.port(graph.getOutput(name), (), iface, True)
        if p is not None:
            out[name] = to_python(p.value)
    return out


@functools.lru_cache(maxsize=1)
def _translated_defaults():
    """The translation graph's outputs for a Standard Surface with every input at its default."""
    params = {n: Parameter(v, "default", "default") for n, (t, v, g) in mxlib.inputs(STANDARD_SURFACE).items() if not g}
    return _translate(list(_translation_dependencies()), params, None)


def _map_standard_surface(m):
    graph_name = mxlib.implementation_graph(TRANSLATION).getName()
    # only the outputs that depend on a set input are evaluated; the rest are the outputs of
    # the all-default Standard Surface (computed once)
    set_inputs = {n for n, p in m.parameters.items() if p.kind != "default"}
    todo = [o for o, d in _translation_dependencies().items() if d & set_inputs]
    values = dict(_translated_defaults())
    values.update(_translate(todo, m.parameters, m))
    mapped = {}
    for name, value in values.items():
        target = name[:-4] if name.endswith("_out") else name
        mapped[target] = Parameter(value, f"{graph_name}.{name} (Standard Surface -> OpenPBR)", "mapped")
    trans_inputs = mxlib.inputs(TRANSLATION)
    unmodelled = [name for name in m.parameters if name not in trans_inputs]
    why = "Standard Surface input without an OpenPBR counterpart"
    return _to_openpbr(m, mapped, STANDARD_SURFACE, unmodelled, why, _STANDARD_SURFACE_APPROXIMATIONS)


#: What the mapping of Standard Surface onto OpenPBR changes.
_STANDARD_SURFACE_APPROXIMATIONS = (
    "diffuse: Standard Surface's Oren-Nayar (QON, sigma = diffuse_roughness in radians, as MaterialX's "
    "standard_surface graph) evaluated as OpenPBRSurface(diffuse_model='qon')",
    f"other inputs mapped to OpenPBR by MaterialX's translation graph {TRANSLATION}: base_color is "
    "multiplied by the coat colour (mixed by coat), specular_weight becomes 1 when metalness > 0 (OpenPBR's "
    "specular_weight also scales the metal), a black specular_color becomes white, thin film and "
    "emission rescaled",
    "the specular/metal Fresnel and the layering are OpenPBR's (exact dielectric Fresnel, F82-tint metal, "
    "albedo scaling), not Standard Surface's own (Schlick-based metal with edge colour)",
)


_PREVIEW_MAP = {
    "diffuseColor": "base_color",
    "metallic": "base_metalness",
    "roughness": "specular_roughness",
    "ior": "specular_ior",
    "clearcoat": "coat_weight",
    "clearcoatRoughness": "coat_roughness",
    "opacity": "geometry_opacity",
}


def _map_preview(m):
    mapped = _renamed(m.parameters, _PREVIEW_MAP, "UsdPreviewSurface")
    spec_workflow = int(m.parameters["useSpecularWorkflow"].value) == 1
    if spec_workflow:
        p = m.parameters["specularColor"]
        mapped["specular_color"] = Parameter(
            p.value,
            f"UsdPreviewSurface specularColor -> specular_color (specular workflow): {p.provenance}",
            "mapped",
            p.authored,
        )
        m.approximations.append(
            "useSpecularWorkflow = 1: specularColor (the preview surface's F0 colour) is used "
            "as OpenPBR's specular_color tint; F0 still comes from ior; metallic is ignored"
        )
        mapped["base_metalness"] = Parameter(0.0, "specular workflow: metallic ignored", "mapped")
    unmodelled = [
        n for n in ("emissiveColor", "normal", "displacement", "occlusion", "opacityThreshold") if n in m.parameters
    ]
    return _to_openpbr(m, mapped, PREVIEW, unmodelled, "UsdPreviewSurface input not modelled", _PREVIEW_APPROXIMATIONS)


#: What the mapping of UsdPreviewSurface onto OpenPBR changes.
_PREVIEW_APPROXIMATIONS = (
    "diffuse: Lambertian, as UsdPreviewSurface defines it: OpenPBRSurface(diffuse_model='lambert')",
    "roughness is the preview surface's specular roughness (-> specular_roughness); the GGX lobe uses "
    "OpenPBR's exact dielectric Fresnel of ior instead of the preview surface's Schlick form",
    "clearcoat maps onto OpenPBR's coat (IOR 1.6 default rather than the preview surface's 1.5)",
)


#: glTF PBR input -> OpenPBR input (MaterialX's ``gltf_pbr`` graph / the glTF 2.0 specification and
#: its KHR_materials_{specular,ior,transmission,clearcoat,sheen,iridescence} extensions).
_GLTF_MAP = {
    "base_color": "base_color",
    "metallic": "base_metalness",
    "roughness": "specular_roughness",
    "ior": "specular_ior",
    "specular": "specular_weight",
    "specular_color": "specular_color",
    "transmission": "transmission_weight",
    "clearcoat": "coat_weight",
    "clearcoat_roughness": "coat_roughness",
    "sheen_color": "fuzz_color",
    "sheen_roughness": "fuzz_roughness",
    "iridescence": "thin_film_weight",
    "iridescence_ior": "thin_film_ior",
}
_GLTF_UNMODELLED = (
    "occlusion",
    "emissive",
    "thickness",
    "attenuation_color",
    "attenuation_distance",
    "anisotropy_strength",
    "anisotropy_rotation",
    "dispersion",
)


def _gltf_opacity(params):
    """geometry_opacity of a glTF material: 1 (OPAQUE), alpha >= alpha_cutoff (MASK), alpha (BLEND)."""
    mode = int(params["alpha_mode"].value)
    alpha = float(params["alpha"].value)
    if mode == 1:
        return (1.0 if alpha >= float(params["alpha_cutoff"].value) else 0.0), "alpha_mode MASK: alpha >= alpha_cutoff"
    if mode == 2:
        return alpha, "alpha_mode BLEND: alpha"
    return 1.0, "alpha_mode OPAQUE: alpha ignored"


def _map_gltf(m):
    """glTF PBR (``ND_gltf_pbr_surfaceshader``) -> OpenPBRSurface(diffuse_model="lambert").

    MaterialX's ``gltf_pbr`` graph uses a bare ``oren_nayar_diffuse_bsdf`` of roughness 0 --
    Lambertian -- for base_color, under a dielectric specular layer (its diffuse is
    base_color x (1 - metallic), attenuated by the layer's Fresnel): OpenPBR's Lambert diffuse
    under its specular layer, with the inputs renamed.
    """
    p = m.parameters
    mapped = _renamed(p, _GLTF_MAP, "glTF PBR")
    sheen = p["sheen_color"].value
    on = any(float(x) != 0.0 for x in (sheen if isinstance(sheen, tuple) else (sheen,)))
    mapped["fuzz_weight"] = Parameter(1.0 if on else 0.0, "glTF PBR sheen_color != 0 -> fuzz_weight 1", "mapped")
    t = p["iridescence_thickness"]
    mapped["thin_film_thickness"] = Parameter(
        float(t.value) / 1000.0,
        f"glTF PBR iridescence_thickness nm -> thin_film_thickness um: {t.provenance}",
        "mapped",
        t.authored,
    )
    mapped["coat_ior"] = Parameter(1.5, "glTF clearcoat IOR 1.5 (KHR_materials_clearcoat)", "mapped")
    opacity, how = _gltf_opacity(p)
    mapped["geometry_opacity"] = Parameter(opacity, f"glTF PBR {how}", "mapped")
    authored = [name for name in _GLTF_UNMODELLED if name in p and p[name].kind != "default"]
    return _to_openpbr(m, mapped, GLTF_PBR, authored, "glTF PBR input not modelled", _GLTF_APPROXIMATIONS)


#: What the mapping of glTF PBR onto OpenPBR changes.
_GLTF_APPROXIMATIONS = (
    "diffuse: Lambertian, as MaterialX's gltf_pbr graph (oren_nayar_diffuse_bsdf of roughness 0): "
    "OpenPBRSurface(diffuse_model='lambert')",
    "the specular layer, metal and clearcoat are OpenPBR's (exact dielectric Fresnel, F82-tint metal, "
    "albedo-scaled layering), not gltf_pbr's generalized Schlick lobes; sheen maps onto OpenPBR's fuzz",
)


def _map_oren_nayar(m):
    out = {n: p for n, p in m.parameters.items() if n != "normal"}
    m.diffuse_model = "eon" if out["energy_compensation"].value else "qon"
    return out


FAMILIES = {
    OPENPBR: Family("OpenPBRSurface", "eon", "acescg", _map_openpbr),
    STANDARD_SURFACE: Family("OpenPBRSurface", "qon", "lin_rec709", _map_standard_surface),
    PREVIEW: Family("OpenPBRSurface", "lambert", "lin_rec709", _map_preview),
    OREN_NAYAR: Family("OrenNayarDiffuseBSDF", "", "lin_rec709", _map_oren_nayar),
    GLTF_PBR: Family("OpenPBRSurface", "lambert", "lin_rec709", _map_gltf),
}


def family(shader_id: str) -> Family | None:
    """The Family of a shader id (after ALIASES), or None."""
    return FAMILIES.get(ALIASES.get(shader_id, shader_id))


# ----------------------------------------------------------------------- clamping
@functools.cache
def _ranges(node_class, diffuse_model):
    """{input: (lo, hi)} of the node's numeric inputs (the nodedef's uimin / uimax)."""
    from ..nodes.materialx_defs import nodedef_inputs

    nd = OPENPBR if node_class == "OpenPBRSurface" else OREN_NAYAR
    r = {
        n: (d.uimin, d.uimax) for n, d in nodedef_inputs(nd).items() if d.type == "float" or d.type.startswith("color")
    }
    if node_class == "OrenNayarDiffuseBSDF":
        # sigma in radians for QON (energy_compensation false), r in [0, 1] for EON
        r["roughness"] = (0.0, 1.0 if diffuse_model == "eon" else math.pi / 2)
    return r


def _inside(v, lo, hi):
    """Fast path: a float or tuple of floats within [lo, hi] (None = unbounded)."""
    vals = v if isinstance(v, tuple) else (v,)
    los = lo if isinstance(lo, tuple) else (lo,) * len(vals)
    his = hi if isinstance(hi, tuple) else (hi,) * len(vals)
    return all(
        isinstance(x, float)
        and x == x
        and (a is None or x >= a)
        and (b is None or x <= b)
        and x not in (math.inf, -math.inf)
        for x, a, b in zip(vals, los, his)
    )


#: Relative distance outside a range that is taken for round-off (of a colour-space
#: conversion) and clamped silently, relative to the value's largest component.
ROUND_OFF = 1e-6


def clamp_inputs(m: Material) -> None:
    """Clamp node inputs to the node's range, with a warning per clamped input (none for a
    value within ``ROUND_OFF`` relative of the range: colour-space round-off)."""
    ranges = _ranges(m.node_class, m.diffuse_model)
    for name, p in list(m.node_inputs.items()):
        if p.kind == "default" or name not in ranges or isinstance(p.value, (bool, str)) or p.value is None:
            continue
        lo, hi = ranges[name]
        if _inside(p.value, lo, hi):
            continue
        v = np.asarray(p.value, dtype=np.float64)
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{m.file}: {m.path}: {name} = {_fmt(p.value)} is not finite")
        lo_a = -np.inf if lo is None else np.asarray(lo, dtype=np.float64)
        hi_a = np.inf if hi is None else np.asarray(hi, dtype=np.float64)
        c = np.minimum(np.maximum(v, lo_a), hi_a)
        if np.array_equal(c, v):
            continue
        value = tuple(float(x) for x in c) if isinstance(p.value, tuple) else float(c)
        scale = float(np.max(np.abs(v)))
        if np.all(np.abs(c - v) <= ROUND_OFF * scale):
            # colour-space round-off (white in ACEScg is 1.0000000186): clamped without a warning
            m.node_inputs[name] = Parameter(value, p.provenance + " (round-off clamped)", p.kind, p.value)
            continue
        rng = f"[{_fmt(lo) if lo is not None else '-inf'}, {_fmt(hi) if hi is not None else 'inf'}]"
        m.warnings.append(
            f"{name} = {_fmt(p.value)} is outside {rng}, the range of the {m.node_class} node: clamped to {_fmt(value)}"
        )
        m.node_inputs[name] = Parameter(value, p.provenance + " (clamped)", p.kind, p.value)


@functools.cache
def _types(node_class):
    """{input: MaterialX type} of the node's inputs."""
    from ..nodes.materialx_defs import nodedef_inputs

    return {n: d.type for n, d in nodedef_inputs(OPENPBR if node_class == "OpenPBRSurface" else OREN_NAYAR).items()}


def check_shapes(m: Material) -> None:
    """ValueError naming the file, material and input when a node input has another number
    of components than its type (the node would refuse it): the material fails, not the file.

    Examples
    --------
    >>> m = Material("M", "/M", "x.usda", "", False, node_class="OpenPBRSurface")
    >>> m.node_inputs = {"base_color": Parameter((0.25, 0.75), "uv", "connection")}
    >>> check_shapes(m)
    Traceback (most recent call last):
    ...
    ValueError: x.usda: material /M: base_color has 2 components, but it is a color3 input (uv)
    """
    types = _types(m.node_class)
    for name, p in m.node_inputs.items():
        t = types.get(name, "")
        want = int(t[-1]) if t[:5] in ("color", "vecto") else 1 if t == "float" else None
        if want is None or p.value is None or isinstance(p.value, (str, bool)):
            continue
        got = np.asarray(p.value).size
        if got != want:
            raise ValueError(
                f"{m.file}: material {m.path}: {name} has {got} components, but it is a {t} input ({p.provenance})"
            )


# ----------------------------------------------------------------------- building
def _unmapped(sid: str, inner: Any) -> str:
    """Why a shader maps onto no node (for a ``surface`` node: the BSDF it wraps)."""
    if sid == "ND_surface":
        what = f"{inner.path} ({inner.shader_id()})" if inner is not None else "nothing connected"
        return (
            f"shader ND_surface maps onto no node of the library: its bsdf is {what}; only a bare "
            f"oren_nayar_diffuse_bsdf is a library node (OrenNayarDiffuseBSDF), other BSDF graphs are not "
            f"evaluated"
        )
    return f"shader {sid or '(none)'} maps onto no node of the library"


def build_material(
    shader: Any,
    *,
    name: str,
    path: str,
    file: str,
    uv: tuple[float, float],
    variants: dict[str, str] | None = None,
    time: float | None = None,
) -> Material:
    """A Material from a shader adapter (MaterialX node or USD shader prim)."""
    m = empty_material(name=name, path=path, file=file, uv=uv, variants=variants, time=time)
    if shader is None or shader.node is None:
        m.unsupported.append("no surface shader is connected to the material")
        return m
    inner = shader.unwrap_surface()
    if (
        inner is not None
        and (inner_family := family(inner.shader_id())) is not None
        and inner_family.node_class == "OrenNayarDiffuseBSDF"
    ):
        m.approximations.append(
            f"surface node {shader.path}: its bsdf {inner.path} is evaluated; the surface's edf and opacity are not"
        )
        shader = inner
    sid = shader.shader_id()
    m.shader_id = sid
    m.shader_path = shader.path
    fam = family(sid)
    if fam is None:
        m.unsupported.append(_unmapped(sid, inner))
        return m
    canonical = ALIASES.get(sid, sid)
    m.parameters = shader.resolve(canonical, fam.default_space, m, uv)
    m.node_class = fam.node_class
    m.diffuse_model = fam.diffuse_model
    m.node_inputs = fam.map(m)
    if m.node_class == "OpenPBRSurface" and m.diffuse_model != "eon" and not diffuse_model_available():
        m.warnings.append(
            f"this OpenPBRSurface has no diffuse_model keyword: the {m.diffuse_model} diffuse of "
            f"{sid} cannot be built (EON would be used); marked unsupported"
        )
        m.unsupported.append(f"diffuse_model {m.diffuse_model!r} (needs OpenPBRSurface(diffuse_model=...))")
        return m
    check_shapes(m)
    clamp_inputs(m)
    m.supported = True
    return m


__all__ = ["FAMILIES", "Family", "family", "build_material", "clamp_inputs", "check_shapes", "ALIASES"]
