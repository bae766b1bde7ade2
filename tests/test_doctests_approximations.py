"""The Examples sections of the approximation modules run as written."""

import doctest
import importlib

import pytest

MODULES = [
    "openpbr_diffuse.approximations.sh",
    "openpbr_diffuse.approximations.gotanda2012",
    "openpbr_diffuse.approximations.kulla_conty",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
