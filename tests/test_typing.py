"""Every public function and method of the package carries type hints.

Public: the names in a module's ``__all__`` and the functions and classes a public module
defines without a leading underscore (a class's own methods, ``__init__`` and ``__call__``
included); numba kernels are checked through their Python function.  The type checker
(``mypy openpbr_diffuse``) checks that the hints are right; this test checks that they are
there, also where mypy is configured to let a function go unannotated.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from collections.abc import Iterator
from types import ModuleType

import pytest

import openpbr_diffuse

#: Sub-packages whose hints are still being completed: their modules are not walked (and
#: names re-exported from them are skipped).  Remove an entry once its package is annotated.
NOT_YET_ANNOTATED: tuple[str, ...] = ()

#: Private top-level modules whose helpers the rest of the package calls: checked as well.
CHECKED_PRIVATE = ("_arrays", "_csv", "_launch", "_signals", "_colour", "_jit")

ROOT = openpbr_diffuse.__name__


def _skipped(module_name: str) -> bool:
    parts = module_name.split(".")[1:]
    return bool(parts) and parts[0] in NOT_YET_ANNOTATED


def _modules() -> Iterator[ModuleType]:
    yield openpbr_diffuse
    for info in pkgutil.walk_packages(openpbr_diffuse.__path__, ROOT + "."):
        parts = info.name.split(".")[1:]
        if _skipped(info.name):
            continue
        private = [p for p in parts if p.startswith("_")]
        if private and not (len(parts) == 1 and parts[0] in CHECKED_PRIVATE):
            continue
        yield importlib.import_module(info.name)


def _public_names(module: ModuleType) -> list[str]:
    names = list(getattr(module, "__all__", ()))
    for name, obj in vars(module).items():
        if not name.startswith("_") and getattr(obj, "__module__", None) == module.__name__ and name not in names:
            names.append(name)
    return names


def missing_hints(func: object) -> list[str]:
    """The parameters (and "return") of ``func`` without an annotation; [] if not a function."""
    func = getattr(func, "py_func", func)  # a numba dispatcher: its Python function
    if not inspect.isfunction(func) or func.__name__ == "<lambda>":
        return []
    sig = inspect.signature(func)
    missing = [
        p.name
        for i, p in enumerate(sig.parameters.values())
        if p.annotation is inspect.Parameter.empty and not (i == 0 and p.name in ("self", "cls"))
    ]
    if sig.return_annotation is inspect.Signature.empty:
        missing.append("return")
    return missing


def _functions(module: ModuleType) -> Iterator[tuple[str, object]]:
    for name in _public_names(module):
        obj = getattr(module, name)
        owner = getattr(obj, "__module__", None) or ""
        if not owner.startswith(ROOT) or _skipped(owner):
            continue  # re-exported from elsewhere (checked there) or not yet annotated
        if inspect.isclass(obj):
            for attr, member in vars(obj).items():
                if attr.startswith("_") and attr not in ("__init__", "__call__"):
                    continue
                if isinstance(member, (staticmethod, classmethod)):
                    member = member.__func__
                elif isinstance(member, property):
                    member = member.fget
                yield f"{owner}.{obj.__qualname__}.{attr}", member
        else:
            yield f"{owner}.{name}", obj


def unannotated() -> list[str]:
    """``module.name: missing, ...`` for every public function or method lacking hints."""
    found = set()
    for module in _modules():
        for where, func in _functions(module):
            missing = missing_hints(func)
            if missing:
                found.add(f"{where}: {', '.join(missing)}")
    return sorted(found)


def test_public_functions_are_annotated():
    missing = unannotated()
    assert not missing, f"{len(missing)} public functions lack type hints:\n" + "\n".join(missing)


def _hinted(x: float, *, k: int = 1) -> float:
    return x * k


def _no_return(x: float):  # noqa: ANN202
    return x


def _no_param(x, y: int) -> int:
    return y


@pytest.mark.parametrize(
    ("func", "expected"),
    [(_hinted, []), (_no_return, ["return"]), (_no_param, ["x"]), (lambda v: v, []), (len, [])],
)
def test_missing_hints_finds_what_is_missing(func, expected):
    assert missing_hints(func) == expected


def test_walk_covers_the_checked_packages():
    walked = {m.__name__.split(".")[1] for m in _modules() if m.__name__ != ROOT}
    for pkg in ("approximations", "spectral", "simulation", "microfacet", "cli", "conformance", "readers"):
        assert pkg in walked
    for pkg in ("models", "albedo", "sampling", "nodes"):
        assert pkg in walked
    for pkg in ("report", "graders", *CHECKED_PRIVATE):
        assert pkg in walked
    assert not walked & set(NOT_YET_ANNOTATED)
