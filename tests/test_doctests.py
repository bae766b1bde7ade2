"""The Examples sections of the public docstrings run as written.

Every public module of the package (no path component starting with "_") is collected
by walking the package, so a new module's examples run without being listed here; the
modules named in ``MUST_HAVE_EXAMPLES`` must also keep at least one example.
Other helpers may add modules of their own in ``tests/test_doctests_<topic>.py``.
"""

import doctest
import importlib
import pkgutil

import pytest
from _system import need

import openpbr_diffuse


def public_modules():
    names = []
    for info in pkgutil.walk_packages(openpbr_diffuse.__path__, "openpbr_diffuse."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        names.append(info.name)
    return sorted(names)


MODULES = public_modules()
MUST_HAVE_EXAMPLES = [
    "openpbr_diffuse.models.api",
    "openpbr_diffuse.sampling.api",
    "openpbr_diffuse.albedo.tables",
    "openpbr_diffuse.nodes.oren_nayar",
    "openpbr_diffuse.nodes.openpbr_surface",
]
#: modules whose examples run a system program's or registry package's code
NEEDS = {"openpbr_diffuse.graders.babylon": ("babylonjs",)}


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    need(*NEEDS.get(name, ()))
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    if name in MUST_HAVE_EXAMPLES:
        assert result.attempted > 0


def test_the_listed_modules_exist():
    assert set(MUST_HAVE_EXAMPLES) <= set(MODULES)
