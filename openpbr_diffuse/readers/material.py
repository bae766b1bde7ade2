"""A material as read from a file: resolved parameters with provenance, and its library node.

``Material.parameters`` are the shader's own inputs (OpenPBR, Standard Surface,
UsdPreviewSurface or oren_nayar_diffuse_bsdf names) as resolved, each a ``Parameter(value,
provenance)``; ``Material.node_inputs`` are the inputs of the library node the material maps
onto (``OpenPBRSurface`` or ``OrenNayarDiffuseBSDF``), after the mapping (``mapping``) and
the clamping to the nodedef's range; ``node()`` builds that node.  Colours are in the
working space, ACEScg (``colorspace.WORKING_SPACE``).
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from ..nodes import OpenPBRSurface, OrenNayarDiffuseBSDF


@dataclass(frozen=True)
class Parameter:
    """One resolved value and where it came from.

    ``value``: float, bool, int, str, or a tuple of floats (colorN / vectorN; colours in the
    working space).  ``provenance``: a readable account ("authored at /M/S.inputs:x",
    "default of ND_...", "connection ... <- texture FILE at uv (u, v)", "time 12").
    ``kind``: "authored", "default", "connection", "texture", "computed" or "mapped".
    ``authored``: the value as written in the file, before colour conversion or clamping
    (None when it is the same as ``value``).
    """

    value: Any
    provenance: str
    kind: str = "authored"
    authored: Any = None

    def to_dict(self) -> dict[str, Any]:
        d = {"value": _jsonable(self.value), "provenance": self.provenance, "kind": self.kind}
        if self.authored is not None:
            d["authored"] = _jsonable(self.authored)
        return d


def _jsonable(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, tuple):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.floating, np.integer, np.bool_)):
        return v.item()
    return v


@dataclass
class Material:
    """A material of a USD stage or MaterialX document (see module docstring).

    Attributes
    ----------
    name : str
        Material prim name or MaterialX material node name.
    path : str
        Prim path (USD) or MaterialX node name path.
    file : str
        The file it was read from.
    shader_id : str
        The surface shader's id (``info:id`` / nodedef name), e.g.
        "ND_open_pbr_surface_surfaceshader", "UsdPreviewSurface".
    supported : bool
        False when the shader maps onto no library node (``node()`` is None).
    parameters : {name: Parameter}
    warnings : [str]
    unsupported : [str]
        Set inputs or graph nodes that the library node does not model / evaluate.
    node_inputs : {name: Parameter}
        Inputs of the library node (after mapping and clamping).
    node_class : str
        "OpenPBRSurface", "OrenNayarDiffuseBSDF" or "".
    diffuse_model : str
        "eon" (OpenPBR), "qon" (Standard Surface), "lambert" (UsdPreviewSurface).
    approximations : [str]
        What the mapping onto the library node approximates.
    shader_path : str
        Path of the surface shader prim / node.
    error : str
        Why the material could not be evaluated ("" when it was read; then ``supported``
        says whether its shader maps onto a library node).  One bad value fails its own
        material, never the file's others.
    """

    name: str
    path: str
    file: str
    shader_id: str
    supported: bool
    parameters: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    unsupported: list = field(default_factory=list)
    node_inputs: dict = field(default_factory=dict)
    node_class: str = ""
    diffuse_model: str = ""
    approximations: list = field(default_factory=list)
    shader_path: str = ""
    variants: dict = field(default_factory=dict)
    time: object = None
    uv: tuple = (0.5, 0.5)
    error: str = ""

    def node_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of the library node (plain values)."""
        kw = {n: p.value for n, p in self.node_inputs.items()}
        if self.node_class == "OpenPBRSurface":
            kw.update(surface_options(self.diffuse_model))
        return kw

    def node(self) -> OpenPBRSurface | OrenNayarDiffuseBSDF | None:
        """The library node (``OpenPBRSurface`` / ``OrenNayarDiffuseBSDF``) or None.

        Inputs the node does not model are already listed in ``unsupported``, so the node's
        own IgnoredInputWarning is silenced here.
        """
        if not self.supported:
            return None
        from ..nodes import OpenPBRSurface, OrenNayarDiffuseBSDF

        cls = {"OpenPBRSurface": OpenPBRSurface, "OrenNayarDiffuseBSDF": OrenNayarDiffuseBSDF}[self.node_class]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return cls(**self.node_kwargs())

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (the ``materials[]`` entry of ``eval --json``)."""
        return {
            "name": self.name,
            "path": self.path,
            "file": self.file,
            "shader_id": self.shader_id,
            "shader_path": self.shader_path,
            "supported": self.supported,
            "node": self.node_class or None,
            "diffuse_model": self.diffuse_model or None,
            "parameters": {n: p.to_dict() for n, p in self.parameters.items()},
            "node_inputs": {n: p.to_dict() for n, p in self.node_inputs.items()},
            "unsupported": list(self.unsupported),
            "approximations": list(self.approximations),
            "warnings": list(self.warnings),
            "time": self.time,
            "variants": dict(self.variants),
            "uv": list(self.uv),
            "error": self.error or None,
        }


def failed_material(
    exc: BaseException,
    *,
    name: str,
    path: str,
    file: str,
    uv: tuple = (0.5, 0.5),
    variants: dict | None = None,
    time: object = None,
) -> Material:
    """A Material that could not be evaluated: ``error`` says why (one line), nothing else set.

    Examples
    --------
    >>> m = failed_material(ValueError("x.mtlx: /M/S.base_color: unknown colour space 'gamma99'"),
    ...                     name="M", path="/M", file="x.mtlx")
    >>> (m.supported, m.error)
    (False, "x.mtlx: /M/S.base_color: unknown colour space 'gamma99'")
    """
    if isinstance(exc, RecursionError):
        text = "the shading graph is nested too deeply to evaluate"
    else:
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        if not isinstance(exc, (ValueError, TypeError, LookupError, OSError)) or not text:
            text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    if file and not text.startswith(str(file)):
        text = f"{file}: {text}"
    return empty_material(name=name, path=path, file=file, uv=uv, variants=variants, time=time, error=text)


def empty_material(
    *,
    name: str,
    path: str,
    file: str,
    uv: tuple = (0.5, 0.5),
    variants: dict | None = None,
    time: object = None,
    error: str = "",
) -> Material:
    """A Material with no shader and nothing resolved (not supported), ``error`` as given.

    What a reader fills in once it has found the material's shader; with ``error``, a
    material that could not be evaluated (see :func:`failed_material`).

    Examples
    --------
    >>> m = empty_material(name="M", path="/M", file="x.usda", uv=(0, 1), variants={"finish": "gloss"})
    >>> (m.shader_id, m.supported, m.uv, m.variants, m.error)
    ('', False, (0.0, 1.0), {'finish': 'gloss'}, '')
    """
    return Material(
        name=name,
        path=path,
        file=str(file),
        shader_id="",
        supported=False,
        uv=tuple(float(x) for x in uv),
        variants=dict(variants or {}),
        time=time,
        error=error,
    )


def surface_options(diffuse_model: str) -> dict[str, str]:
    """Keyword arguments selecting the diffuse model of OpenPBRSurface.

    ``diffuse_model`` is a keyword of OpenPBRSurface ("eon", "qon", "lambert"); when the
    installed OpenPBRSurface predates it, "eon" needs no keyword and other models raise
    (see ``diffuse_model_available``).
    """
    if diffuse_model_available():
        return {"diffuse_model": diffuse_model}
    if diffuse_model in ("", "eon"):
        return {}
    raise ValueError(f"this OpenPBRSurface has no diffuse_model keyword; cannot build a {diffuse_model!r} diffuse")


@functools.lru_cache(maxsize=1)
def diffuse_model_available():
    """Whether OpenPBRSurface takes ``diffuse_model`` (checked once)."""
    from ..nodes import OpenPBRSurface

    return "diffuse_model" in OpenPBRSurface.signature().parameters


__all__ = ["Parameter", "Material", "empty_material", "failed_material", "surface_options", "diffuse_model_available"]
