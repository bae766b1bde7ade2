"""What a grader needs from an implementation: its own code wrapped as array functions.

A :class:`Subject` is one implementation made callable on NumPy arrays, in the project's
conventions (local frame, +z normal, ``wi`` towards the light and ``wo`` towards the viewer,
both pointing away from the surface; BRDF values without the cosine).  Every callable runs the
implementation's own code (GLSL on llvmpipe, a compiled C++ harness, a Cycles render); what it
does not offer is ``None``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass
class Subject:
    """An implementation under test.

    Attributes
    ----------
    name : str
        Registry name (``"materialx-glsl"``, ...) or ``"glsl:FILE:FUNCTION"`` for the adapters.
    model : str
        The reference model its code claims to implement (``"eon"``).
    tolerance : (float, float)
        (relative, absolute) tolerance passed to ``conformance.grade.grade``, and
        ``tolerance_reason`` why.
    version : dict
        What was run: library versions, source path, SHA-256 of the sources.
    brdf : callable or None
        ``brdf(wi (n,3), wo (n,3), roughness (n,), rho (n,3)) -> (n,3)`` f without cosine.
    albedo : callable or None
        ``albedo(mu (n,), roughness (n,), rho (n,3)) -> (n,3)`` directional albedo.
    sample : callable or None
        ``sample(wo (n,3), roughness (n,), u (n,2)) -> (wi (n,3), pdf (n,))``.
    pdf : callable or None
        ``pdf(wo (n,3), wi (n,3), roughness (n,)) -> (n,)``.
    surface : callable or None
        ``surface(inputs: dict, wo (n,3)) -> {"weight": (n,3), "probability": (n,)}``: the
        diffuse lobe's weight and selection probability inside the implementation's surface.
    selection : str or None
        How the surface picks a lobe (``"length"`` or ``"max"`` of |w E|), for ``OpenPBRSurface``.
    brdf_domain : callable or None
        ``brdf_domain(wi, wo) -> (n,) bool``: the rows inside the implementation's documented
        input domain (e.g. a view direction face-forwarded to the normal); rows outside it are
        not graded and are reported as such.  ``albedo_domain(mu) -> (n,) bool`` likewise.
    paths : list of (str, Subject)
        For an implementation whose lobe is computed differently per code path (Babylon.js: one
        per light type): ``(label, subject)`` pairs, each graded on its own; the quantities are
        named ``"<kind> <label>"``.
    """

    name: str
    model: str
    tolerance: tuple | None
    tolerance_reason: str
    version: dict = field(default_factory=dict)
    brdf: Callable | None = None
    albedo: Callable | None = None
    sample: Callable | None = None
    pdf: Callable | None = None
    surface: Callable | None = None
    brdf_domain: Callable | None = None
    albedo_domain: Callable | None = None
    selection: str | None = None
    notes: list = field(default_factory=list)
    noise: dict = field(default_factory=dict)
    paths: list = field(default_factory=list)
