"""The Examples of the layered modules run as written."""

import doctest
import importlib

import pytest

MODULES = [
    "openpbr_diffuse.simulation.layered",
    "openpbr_diffuse.approximations.gotanda2012_layered",
    "openpbr_diffuse.approximations.weidlich_wilkie",
    "openpbr_diffuse.approximations.layering_grading",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
