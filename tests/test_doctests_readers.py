"""The readers' public modules keep runnable Examples (the generic doctest runner of
tests/test_doctests.py runs them; here: that they exist and pass)."""

import doctest
import importlib

import pytest

MODULES = ["openpbr_diffuse.readers.api", "openpbr_diffuse.readers.colorspace", "openpbr_diffuse.readers.ops"]


@pytest.mark.parametrize("name", MODULES)
def test_readers_examples_run(name):
    mod = importlib.import_module(name)
    res = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.attempted > 0 and res.failed == 0
