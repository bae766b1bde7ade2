"""The package's imports go one way down: no import circle, no reaching into a sibling's
private module.

Checked by parsing every module's source (``ast``), independent of what happens to be
imported at run time: every ``import`` / ``from ... import`` statement (also those inside
functions, the lazy ones) is resolved to a module of the package.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "openpbr_diffuse"


def _module_name(path):
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules():
    return {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


MODULES = _modules()


def _resolve(base, level, name, is_package):
    """Absolute name of a (possibly relative) import in module ``base``."""
    if level == 0:
        return name
    parts = base.split(".")
    if not is_package:
        parts = parts[:-1]
    parts = parts[: len(parts) - (level - 1)]
    return ".".join(parts + ([name] if name else []))


def imports_of(name):
    """Modules of the package that ``name`` imports (statement -> most specific module)."""
    path = MODULES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            mod = _resolve(name, node.level, node.module or "", is_package)
            targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in MODULES else mod for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in MODULES:
                t = t.rpartition(".")[0]
            if t and t != name:
                found.add(t)
    return found


GRAPH = {name: imports_of(name) for name in MODULES}


def _package(name):
    """The sub-package a module belongs to (``openpbr_diffuse.models``), or the top module."""
    parts = name.split(".")
    return ".".join(parts[:2])


def _cycle(graph):
    """A cycle of the directed graph as a list of nodes, or None."""
    WHITE, GREY, BLACK = 0, 1, 2
    colour = {n: WHITE for n in graph}
    stack = []

    def visit(n):
        colour[n] = GREY
        stack.append(n)
        for m in sorted(graph.get(n, ())):
            if colour.get(m, BLACK) == GREY:
                return stack[stack.index(m) :] + [m]
            if colour.get(m) == WHITE:
                c = visit(m)
                if c:
                    return c
        stack.pop()
        colour[n] = BLACK
        return None

    for n in sorted(graph):
        if colour[n] == WHITE:
            c = visit(n)
            if c:
                return c
    return None


def test_the_parser_sees_the_imports():
    # a check of the checker: known edges are found, relative and lazy ones included
    assert "openpbr_diffuse._jit" in GRAPH["openpbr_diffuse.models.qon"]
    assert "openpbr_diffuse.models.api" in GRAPH["openpbr_diffuse.albedo.generate"]
    assert "openpbr_diffuse.models.tables" in GRAPH["openpbr_diffuse.models.api"]  # a lazy import
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]


def test_no_import_circle_between_modules():
    assert _cycle(GRAPH) is None, " -> ".join(_cycle(GRAPH))


def test_no_import_circle_between_subpackages():
    pkgs = {}
    for name, deps in GRAPH.items():
        if name == "openpbr_diffuse":  # the top-level __init__ re-exports everything
            continue
        pkgs.setdefault(_package(name), set()).update(
            _package(d) for d in deps if _package(d) != _package(name) and d != "openpbr_diffuse"
        )
    cycle = _cycle(pkgs)
    assert cycle is None, " -> ".join(cycle)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_private_module_of_a_sibling_package(name):
    """A module may import private modules (``_x``) of its own package or of an ancestor
    package (``openpbr_diffuse._jit``), never those inside another sub-package."""
    own = name.split(".")
    if MODULES[name].name != "__init__.py":
        own = own[:-1]
    for dep in GRAPH[name]:
        parts = dep.split(".")
        for k, part in enumerate(parts):
            if part.startswith("_") and k > 0:
                owner = parts[:k]  # the package that holds the private module
                assert own[: len(owner)] == owner, f"{name} imports {dep}, private to {'.'.join(owner)}"


def _numba_calls(tree):
    """The ``numba.njit`` / ``numba.jit`` / ``numba.vectorize`` calls and decorators of a module."""
    names = {"njit", "jit", "vectorize", "guvectorize", "cfunc", "generated_jit"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "numba":
            if node.attr in names:
                yield node
        elif isinstance(node, ast.ImportFrom) and node.module == "numba":
            for alias in node.names:
                if alias.name in names:
                    yield node


def test_every_compile_decorator_is_made_in_jit():
    """The compile settings live in one module (``_jit``): the others decorate with its names."""
    found = {
        name: [n.lineno for n in _numba_calls(ast.parse(path.read_text()))]
        for name, path in MODULES.items()
        if name != "openpbr_diffuse._jit"
    }
    assert {k: v for k, v in found.items() if v} == {}
    assert list(_numba_calls(ast.parse(MODULES["openpbr_diffuse._jit"].read_text())))  # the test sees them


def test_the_decorators_without_reference_counting_compile_without_it():
    """``block``, ``driver``, ``serial`` and the surface's ``runner`` (its scratch is a stack
    pointer) are built without numba's reference counting; ``kernel`` (a formula may be given
    arrays from Python), ``reduction`` and ``walk`` (they allocate) keep it, as does a block
    kernel's Python twin.  None of the cached entry points builds numba's C wrapper."""
    from openpbr_diffuse import _jit
    from openpbr_diffuse.models.eon import rho_ms
    from openpbr_diffuse.nodes._surface_kernels import _pack_weights, pack_drive

    assert _pack_weights.targetoptions["_nrt"] is False
    assert "_nrt" not in _pack_weights.python_twin.targetoptions
    assert "_nrt" not in rho_ms.targetoptions
    assert pack_drive.targetoptions["_nrt"] is False
    for deco in (_jit.driver, _jit.serial, _jit.runner):
        assert deco(lambda x: x).targetoptions["_nrt"] is False
    for deco in (_jit.reduction, _jit.walk):
        assert "_nrt" not in deco(lambda x: x).targetoptions
    for deco in (_jit.driver, _jit.serial, _jit.runner, _jit.walk):
        assert deco(lambda x: x).targetoptions["no_cfunc_wrapper"] is True
