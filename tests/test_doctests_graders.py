"""The Examples sections of the grader modules run as written."""

import doctest
import importlib

import pytest

MODULES = ["openpbr_diffuse.graders.chi2", "openpbr_diffuse.graders._arrays", "openpbr_diffuse.graders.materialx"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
