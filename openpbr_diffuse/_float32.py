"""float32 twins of the scalar formulas: the same source, with float32 constants.

numba types a Python float (a literal ``1.0``, a module constant such as ``INV_PI``) as
float64, and float32 combined with float64 gives float64: a formula written once with
Python constants and called with float32 arguments computes in float64.  ``float32_twin``
compiles a second copy of a formula (``_jit.kernel``) whose float constants are float32:
its source is parsed, every float literal, every float module constant it reads and the
float attributes of ``math`` (``math.pi``, ``math.nan``) become float32 values, and every
formula it calls becomes that formula's own twin.  Called with float32 arguments, the twin
computes in float32 throughout (LLVM then vectorises twice as many rows per instruction
as in float64); the float64 formula is not touched.

The twins are what the float32 batch drivers of the models call (``models._kernels``);
their accuracy against the float64 path is measured in ``tests/test_float32.py``.
"""

import ast
import functools
import inspect
import math
import textwrap
from typing import Any

import numpy as np

from ._jit import _Kernel

_MATH_FLOATS = {name: getattr(math, name) for name in ("pi", "e", "tau", "inf", "nan")}


def _is_float(value: object) -> bool:
    return isinstance(value, (float, np.floating)) and not isinstance(value, bool)


class _Retype(ast.NodeTransformer):
    """Float literals and float globals to float32 names; calls of formulas to their twins."""

    def __init__(self, globs: dict[str, Any], env: dict[str, Any]) -> None:
        self.globs, self.env = globs, env

    def _const(self, value: float) -> ast.Name:
        name = f"_f32_{len(self.env)}"
        self.env[name] = np.float32(value)
        return ast.Name(name, ast.Load())

    def visit_Constant(self, node: ast.Constant) -> ast.AST:
        value = node.value
        return self._const(value) if isinstance(value, (float, np.floating)) else node

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:
        if isinstance(node.value, ast.Name) and self.globs.get(node.value.id) is math and node.attr in _MATH_FLOATS:
            return self._const(_MATH_FLOATS[node.attr])
        return self.generic_visit(node)

    def visit_Name(self, node: ast.Name) -> ast.AST:
        if isinstance(node.ctx, ast.Load) and node.id in self.globs:
            value = self.globs[node.id]
            if _is_float(value):
                return self._const(value)
            if isinstance(value, _Kernel):
                twin = f"_twin_{node.id}"
                self.env[twin] = float32_twin(value)
                return ast.Name(twin, ast.Load())
        return node


@functools.cache
def float32_twin(formula: Any) -> Any:
    """The float32 copy of a compiled formula (a ``_jit.kernel``; see the module docstring),
    compiled with the formula's own options; built once per formula.

    Example
    -------
    >>> import numpy as np
    >>> from openpbr_diffuse.models.fon import fon_A
    >>> x, y = float32_twin(fon_A)(np.float32(0.5)), fon_A(np.float32(0.5))
    >>> x == float(np.float32(x)), y == float(np.float32(y))   # computed in float32, in float64
    (True, False)
    """
    f = formula.py_func
    tree = ast.parse(textwrap.dedent(inspect.getsource(f)))
    fn = tree.body[0]
    assert isinstance(fn, ast.FunctionDef)
    fn.decorator_list = []
    fn.returns = None
    for a in fn.args.args:
        a.annotation = None
    env: dict[str, Any] = {}
    fn = _Retype(f.__globals__, env).visit(fn)
    fn.name = f.__name__ + "__float32"
    module = ast.fix_missing_locations(ast.Module(body=[fn], type_ignores=[]))
    namespace = dict(f.__globals__, **env)
    exec(compile(module, inspect.getsourcefile(f) or "<float32>", "exec"), namespace)
    twin = namespace[fn.name]
    twin.__qualname__ = f.__qualname__ + "__float32"
    twin.__module__, twin.__doc__ = f.__module__, f.__doc__
    # compiled as the formula is (``kernel``, ``predicate``: same options)
    return _Kernel(py_func=twin, locals={}, targetoptions=dict(formula.targetoptions))
