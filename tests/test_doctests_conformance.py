"""The Examples sections of the conformance and report modules run as written."""

import doctest
import importlib

import pytest

MODULES = [
    "openpbr_diffuse.conformance.vectors",
    "openpbr_diffuse.conformance.deviations",
    "openpbr_diffuse.sampling.quality",
    "openpbr_diffuse.report.render",
    "openpbr_diffuse.conformance.grade",
    "openpbr_diffuse.conformance.properties",
    "openpbr_diffuse.conformance.terms",
    "openpbr_diffuse.conformance.tiers",
    "openpbr_diffuse.conformance.templates",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
