"""Evaluate materials with their library nodes: the diffuse lobe's weight, selection
probability and albedo, the directional albedo and BRDF values at given directions.

Directions are given as angles in degrees in the local frame (normal +z):
wo = (sin theta_o, 0, cos theta_o), wi = (sin theta_i cos phi, sin theta_i sin phi, cos theta_i);
phi is the azimuth of wi relative to wo (180 = the plane of incidence, forward scattering).

``evaluate_many`` evaluates thousands of materials at once: materials with the same node and
diffuse model are stacked into one node with array-valued inputs (the nodes broadcast their
inputs), so the cost is one vectorised call per group, not per material.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..nodes.openpbr_surface import MODELLED

if TYPE_CHECKING:
    from ..nodes import OpenPBRSurface, OrenNayarDiffuseBSDF
    from .material import Material


def directions(
    theta_i: ArrayLike, theta_o: ArrayLike, phi: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(wi, wo) unit vectors (..., 3) from angles in degrees (broadcast together)."""
    ti, to, ph = np.broadcast_arrays(*(np.radians(np.asarray(a, dtype=np.float64)) for a in (theta_i, theta_o, phi)))
    wi = np.stack([np.sin(ti) * np.cos(ph), np.sin(ti) * np.sin(ph), np.cos(ti)], axis=-1)
    wo = np.stack([np.sin(to), np.zeros_like(to), np.cos(to)], axis=-1)
    return wi, wo


def check_angles(name: str, values: ArrayLike) -> NDArray[np.float64]:
    a = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite degrees, got {values!r}")
    if name != "phi" and (np.any(a < 0.0) or np.any(a > 90.0)):
        raise ValueError(f"{name} must lie in [0, 90] degrees, got {values!r}")
    return a


def evaluate(
    material: Material, theta_i: ArrayLike = (30.0,), theta_o: ArrayLike = (30.0,), phi: ArrayLike = (180.0,)
) -> dict[str, Any]:
    """Evaluate one material at the given directions.

    Returns
    -------
    dict with keys (None values for an unsupported material):
        theta_i, theta_o, phi (degrees, broadcast), brdf (n, 3) BSDF without the cosine,
        albedo (n, 3) directional albedo at theta_o, diffuse: {weight (n, 3), albedo (n, 3),
        probability (n,), contribution (n, 3) = weight * albedo}, lobes: [{name,
        probability (n,)}].
    """
    ti, to, ph = np.broadcast_arrays(
        *(np.atleast_1d(check_angles(n, v)) for n, v in (("theta_i", theta_i), ("theta_o", theta_o), ("phi", phi)))
    )
    out = {
        "theta_i": ti.tolist(),
        "theta_o": to.tolist(),
        "phi": ph.tolist(),
        "brdf": None,
        "albedo": None,
        "diffuse": None,
        "lobes": [],
    }
    node = material.node()
    if node is None:
        return out
    wi, wo = directions(ti, to, ph)
    brdf, albedo, out["diffuse"], out["lobes"] = brdf_and_lobes(node, wi, wo)
    out["brdf"] = brdf.tolist()
    out["albedo"] = albedo.tolist()
    return out


def brdf_and_lobes(
    node: OpenPBRSurface | OrenNayarDiffuseBSDF, wi: NDArray[np.float64], wo: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, Any], list[dict[str, Any]]]:
    """(BSDF at (wi, wo), directional albedo at wo, diffuse lobe, lobe listing) of a node.

    A surface's come from one compiled pass (``OpenPBRSurface.lobes_and_eval``), its albedo
    the sum of its lobes' w_k E_k (what ``OpenPBRSurface.albedo`` returns, to rounding): a
    command's first run compiles one surface driver where it compiled three (eval, lobes,
    albedo)."""
    if not hasattr(node, "lobes_and_eval"):
        diffuse, listing = diffuse_lobe(node, wo)
        brdf = np.asarray(node.eval(wi, wo), dtype=np.float64)
        return brdf, np.asarray(diffuse["contribution"], dtype=np.float64), diffuse, listing
    n = wo.shape[0] if wo.ndim > 1 else 1
    lobes, brdf = node.lobes_and_eval(wi, wo)
    diffuse, listing = _diffuse_of(lobes, n)
    total = np.zeros((n, 3))
    for lb in lobes:
        total += np.broadcast_to(lb.weight, (n, 3)) * np.broadcast_to(lb.albedo, (n, 3))
    return np.asarray(brdf, dtype=np.float64), total, diffuse, listing


def _diffuse_of(lobes: Sequence[Any], n: int) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """``diffuse_lobe``'s answer from a surface's ``lobes(wo)`` at n rows."""
    listing = [{"name": lb.name, "probability": np.broadcast_to(lb.probability, (n,)).tolist()} for lb in lobes]
    d = next((lb for lb in lobes if lb.name == "diffuse"), None)
    if d is None:
        zero = np.zeros((n, 3))
        return (
            {
                "weight": zero.tolist(),
                "albedo": zero.tolist(),
                "probability": [0.0] * n,
                "contribution": zero.tolist(),
            },
            listing,
        )
    w = np.broadcast_to(d.weight, (n, 3))
    E = np.broadcast_to(d.albedo, (n, 3))
    return (
        {
            "weight": w.tolist(),
            "albedo": E.tolist(),
            "probability": np.broadcast_to(d.probability, (n,)).tolist(),
            "contribution": (w * E).tolist(),
        },
        listing,
    )


def diffuse_lobe(
    node: OpenPBRSurface | OrenNayarDiffuseBSDF, wo: NDArray[np.float64]
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """({weight, albedo, probability, contribution}, [{name, probability}]) of a node at wo."""
    n = wo.shape[0] if wo.ndim > 1 else 1
    if hasattr(node, "lobes"):
        return _diffuse_of(node.lobes(wo), n)
    # OrenNayarDiffuseBSDF: one lobe, weight * f(color)
    E = np.broadcast_to(node.albedo(wo), (n, 3))
    w = np.broadcast_to(np.asarray(node.weight, dtype=np.float64)[..., None] * np.ones(3), (n, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        own = np.where(w > 0, E / np.where(w > 0, w, 1.0), 0.0)
    return (
        {"weight": w.tolist(), "albedo": own.tolist(), "probability": [1.0] * n, "contribution": E.tolist()},
        [{"name": "diffuse", "probability": [1.0] * n}],
    )


def _group_key(m):
    """Materials stack into one node when they share the node, the diffuse model and every
    boolean (uniform) input such as geometry_thin_walled."""
    flags = tuple(sorted((n, p.value) for n, p in m.node_inputs.items() if isinstance(p.value, bool)))
    return (m.node_class, m.diffuse_model, flags)


def stacked_node(materials: Sequence[Material]) -> OpenPBRSurface | OrenNayarDiffuseBSDF:
    """One library node whose inputs are the stacked inputs of ``materials`` (same node class
    and diffuse model); only the modelled inputs are stacked."""
    from ..nodes import OpenPBRSurface, OrenNayarDiffuseBSDF
    from .material import surface_options

    first = materials[0]
    if first.node_class == "OpenPBRSurface":
        names = [n for n in first.node_inputs if n in MODELLED]
        kw = {
            n: (
                first.node_inputs[n].value
                if isinstance(first.node_inputs[n].value, bool)
                else np.array([m.node_inputs[n].value for m in materials], dtype=np.float64)
            )
            for n in names
        }
        kw.update(surface_options(first.diffuse_model))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return OpenPBRSurface(**kw)
    kw = {
        n: np.array([m.node_inputs[n].value for m in materials], dtype=np.float64)
        for n in ("weight", "color", "roughness")
    }
    return OrenNayarDiffuseBSDF(**kw, energy_compensation=bool(first.node_inputs["energy_compensation"].value))


def evaluate_many(
    materials: Sequence[Material], theta_i: float = 30.0, theta_o: float = 30.0, phi: float = 180.0
) -> dict[str, Any]:
    """Evaluate many materials at one direction pair, vectorised per group.

    Returns
    -------
    dict with arrays over the materials (unsupported ones NaN): brdf (N, 3), albedo (N, 3),
    diffuse_weight (N, 3), diffuse_probability (N,).
    """
    N = len(materials)
    out: dict[str, NDArray[np.float64]] = {k: np.full((N, 3), np.nan) for k in ("brdf", "albedo", "diffuse_weight")}
    out["diffuse_probability"] = np.full(N, np.nan)
    groups: dict[Any, list[int]] = {}
    for i, m in enumerate(materials):
        if m.supported:
            groups.setdefault(_group_key(m), []).append(i)
    wi, wo = directions(theta_i, theta_o, phi)
    for idx in groups.values():
        node = stacked_node([materials[i] for i in idx])
        # directions broadcast to one row per material (the nodes' inputs are (n,) / (n, 3))
        wig, wog = np.broadcast_to(wi, (len(idx), 3)), np.broadcast_to(wo, (len(idx), 3))
        out["brdf"][idx], out["albedo"][idx], d, _ = brdf_and_lobes(node, wig, wog)
        out["diffuse_weight"][idx] = d["weight"]
        out["diffuse_probability"][idx] = d["probability"]
    return out


__all__ = ["brdf_and_lobes", "directions", "evaluate", "evaluate_many", "diffuse_lobe", "stacked_node"]
