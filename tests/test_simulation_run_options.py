"""The run options every ``simulate_*`` takes are checked once (``simulation._run.RunOptions``)
and mean the same in the microsurface and the layered simulators."""

import doctest

import pytest

from openpbr_diffuse.simulation import _run
from openpbr_diffuse.simulation.api import simulate_albedo
from openpbr_diffuse.simulation.layered import LayeredSurface, simulate_layered_albedo


@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        ({"paths": 0}, ValueError, "paths must be an integer >= 1"),
        ({"seed": -1}, ValueError, "seed must be an integer >= 0"),
        ({"workers": 0}, ValueError, "workers must be an integer >= 1"),
        ({"paths": True}, TypeError, "paths must be an integer"),
        ({"client": object(), "scheduler": "tcp://127.0.0.1:1"}, ValueError, "not both"),
    ],
)
def test_both_simulators_reject_the_same_options_by_keyword(kwargs, error, words):
    with pytest.raises(error, match=words):
        simulate_albedo("vcavity", 0.0, [0.5], **kwargs)
    layered = {**kwargs, "paths": 1} if kwargs.get("paths") == 0 else kwargs  # its minimum is 2
    with pytest.raises(error, match=words.replace(">= 1", ">= 2") if "paths" in words else words):
        simulate_layered_albedo(LayeredSurface("smooth", 1.0), [0.5], **layered)


def test_the_same_seed_gives_the_same_result_on_one_thread_or_two():
    a = simulate_albedo("smith-ggx", 0.5, [0.3], rho=0.6, paths=70_000, seed=4, workers=1)
    b = simulate_albedo("smith-ggx", 0.5, [0.3], rho=0.6, paths=70_000, seed=4, workers=2)
    assert (a.albedo == b.albedo).all() and (a.stderr == b.stderr).all()


def test_run_examples():
    result = doctest.testmod(_run)
    assert result.failed == 0 and result.attempted >= 5
