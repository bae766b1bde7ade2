"""Grade real implementations by running their own code, and name their deviation.

Each implementation is wrapped as a :class:`~.subject.Subject` whose callables run its own
code: GLSL on Mesa's llvmpipe (:mod:`.glsl`), C++ through a harness compiled at run time
(:mod:`.cpp`), Blender Cycles through renders (:mod:`.cycles`).  :func:`grade_implementation`
grades BRDF values and albedos exactly as ``check FILE`` does (``conformance.grade.grade`` on the
default vectors), plus samplers and, for surface implementations, the diffuse lobe's weight and
selection probability.

=====================  ==========================================================  =========
name                   code run                                                    --source
=====================  ==========================================================  =========
materialx-glsl         MaterialX wheel: pbrlib/genglsl/mx_oren_nayar_diffuse_bsdf   optional
materialx-glsl-qon     the same node with energy_compensation = false (QON)         optional
cycles                 bpy (Blender) Cycles Diffuse BSDF, rendered                  unused
babylonjs              npm @babylonjs/core: EON as each light type computes it      optional
threejs                npm three: BRDF_EON / EON_DirectionalAlbedo (GLSL chunks)    optional
three-gpu-pathtracer   npm three-gpu-pathtracer: eonBrdf, fonBrdf, EON sampler (WGSL) optional
=====================  ==========================================================  =========

Code that is not installed by a package -- a checkout of another project, your own
renderer's lobe -- is graded with the generic adapters (:mod:`.generic`: ``check --glsl FILE``
/ ``check --cpp FILE`` with the documented signatures).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from .errors import GraderUnavailable

if TYPE_CHECKING:
    from ..conformance.vectors import VectorSet
    from .grading import ImplementationGrade
    from .subject import Subject


@dataclass(frozen=True)
class Implementation:
    """A registered implementation: how to build its subject and where its code lives."""

    name: str
    module: str
    needs_source: bool
    upstream: str
    options: tuple = ()  # (keyword, value) pairs for the module's subject()

    def factory(self) -> Callable:
        import functools
        import importlib

        return functools.partial(importlib.import_module(f"{__name__}.{self.module}").subject, **dict(self.options))


IMPLEMENTATIONS = {
    i.name: i
    for i in (
        Implementation("materialx-glsl", "materialx", False, "pip install MaterialX"),
        Implementation(
            "materialx-glsl-qon", "materialx", False, "pip install MaterialX", (("energy_compensation", False),)
        ),
        Implementation("cycles", "cycles", False, "pip install bpy"),
        Implementation("babylonjs", "babylon", False, "npm install @babylonjs/core"),
        Implementation("threejs", "threejs", False, "npm install three"),
        Implementation("three-gpu-pathtracer", "threejs_pathtracer", False, "npm install three-gpu-pathtracer"),
    )
}


def load(name: str, source: Path | str | None = None) -> Subject:
    """The :class:`~.subject.Subject` of a registered implementation.

    Raises
    ------
    ValueError
        ``name`` is not registered.
    GraderUnavailable
        A piece it needs is missing (its source, a GL driver, a compiler, bpy).
    """
    if name not in IMPLEMENTATIONS:
        raise ValueError(f"implementation: {name!r} is not one of {', '.join(IMPLEMENTATIONS)}")
    impl = IMPLEMENTATIONS[name]
    if impl.needs_source and source is None:
        raise GraderUnavailable(
            f"{name}: its source is not bundled with a package: pass --source PATH (a checkout of {impl.upstream})"
        )
    return impl.factory()(Path(source) if source is not None else None)


def grade_implementation(
    name: str, source: Path | str | None = None, *, quick: bool = False, vectors: VectorSet | None = None
) -> ImplementationGrade:
    """Run implementation ``name``'s own code and grade it: an :class:`~.grading.ImplementationGrade`."""
    from .grading import grade_subject

    return grade_subject(load(name, source), quick=quick, vectors=vectors)


__all__ = ["IMPLEMENTATIONS", "GraderUnavailable", "Implementation", "grade_implementation", "load"]
