"""The Examples of the simulation API run as written."""

import doctest
import importlib

import pytest

MODULES = ["openpbr_diffuse.simulation.api"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
