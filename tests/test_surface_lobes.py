"""The lobes of ``OpenPBRSurface`` as modules of a registry (``nodes.lobes``), and its inputs
declared once (``nodes.surface_inputs``).

A lobe added to the registry at run time -- its module and one row, then the engine's modules
assembled again (imported anew) -- is compiled into every verb; the toy lobe here is a constant-albedo Lambertian lobe on top of the layers, weighted
by an unmodelled input of the nodedef, so its BSDF, albedo, pdf and samples are known in
closed form (f = w a / pi over the upper hemisphere, pdf = cos / pi).
"""

import json
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse import OpenPBRSurface
from openpbr_diffuse.nodes import _surface_drivers as sd
from openpbr_diffuse.nodes import _surface_kernels as sk
from openpbr_diffuse.nodes import lobes, surface_inputs
from openpbr_diffuse.nodes._surface_params import D_EON, D_QON, ON_TOP, UNDER_COAT, UNDER_FUZZ, UNDER_SPECULAR
from openpbr_diffuse.nodes.materialx_defs import nodedef_inputs
from openpbr_diffuse.nodes.openpbr_surface import MODELLED, IgnoredInputWarning

ROOT = Path(__file__).resolve().parents[1]

TOY = '''
"""A toy lobe: Lambertian, albedo ALBEDO, weight thin_film_weight, on top of the layers."""
from openpbr_diffuse._jit import INV_PI, block
from openpbr_diffuse.nodes._surface_params import ON_TOP, S_COSINE

NAME = "toy"
LAYER = ON_TOP
INPUTS = ("thin_film_weight",)
ALBEDO = 0.6


@block
def weight_color(p, offset, c):
    return p[offset + INPUT.thin_film_weight]


@block
def constant_albedo(p, offset, c):
    return ALBEDO


@block
def is_on(p, offset):
    return p[offset + INPUT.thin_film_weight] > 0.0


@block
def eval(p, offset, d, x):
    v = ALBEDO * INV_PI if (d.wi_z > 0.0) & (d.wo_z > 0.0) else 0.0
    return v, v, v


@block
def pdf(p, offset, d, dmodel, vndf, ggx_pdf):
    return d.wi_z * INV_PI if d.wi_z > 0.0 else 0.0


@block
def sampler(dmodel):
    return S_COSINE


@block
def sample_setup(p, offset):
    return 0.0, 1.0


@block
def albedo(c, p, offset, ms, st):
    return ALBEDO


@block
def score(mx, p, offset, weight_at, constant, ms, st):
    return constant
'''

CHILD = '''
import json, sys, warnings
import numpy as np
import importlib
import toy_lobe
from openpbr_diffuse.nodes import _surface_drivers, _surface_kernels, _surface_passes, lobes, openpbr_surface

lobes.register(toy_lobe)  # the row; the engine is then assembled again from the registry
for module in (_surface_kernels, _surface_passes, _surface_drivers, openpbr_surface):
    importlib.reload(module)
OpenPBRSurface = openpbr_surface.OpenPBRSurface

rng = np.random.default_rng(11)
wi, wo = rng.normal(size=(2, 64, 3))
wo[:, 2] = np.abs(wo[:, 2])
wi /= np.linalg.norm(wi, axis=1)[:, None]
wo /= np.linalg.norm(wo, axis=1)[:, None]
with warnings.catch_warnings():
    warnings.simplefilter("error")  # the toy's input is modelled now: no IgnoredInputWarning
    s = OpenPBRSurface(base_weight=0.0, specular_weight=0.0, thin_film_weight=0.5)
found, f = s.lobes_and_eval(wi, wo)
json.dump(
    {
        "names": [lobe.name for lobe in found],
        "weight": found[0].weight.tolist(),
        "albedo": found[0].albedo.tolist(),
        "probability": found[0].probability.tolist(),
        "f": f.tolist(),
        "wi": wi.tolist(),
        "wo": wo.tolist(),
    },
    open(sys.argv[1], "w"),
)
'''


@pytest.mark.slow
def test_a_lobe_added_by_a_registry_row_is_compiled_into_the_surface(tmp_path):
    """Module + row: the toy lobe is the surface's only lobe (base_weight = specular_weight =
    0), and its weight, albedo, probability and BSDF equal the closed forms.  Runs in a child
    with its own numba cache (the whole engine compiles for nine lobes: about a minute)."""
    (tmp_path / "toy_lobe.py").write_text(TOY)
    env = dict(
        os.environ,
        NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"),
        PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT), os.environ.get("PYTHONPATH", "")]),
    )
    out = tmp_path / "out.json"
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(out)], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-3000:]
    r = json.loads(out.read_text())
    wi = np.array(r["wi"])
    assert r["names"] == ["toy"]
    np.testing.assert_array_equal(r["weight"], np.full((64, 3), 0.5))  # on top: L = 1
    np.testing.assert_array_equal(r["albedo"], np.full((64, 3), 0.6))
    np.testing.assert_array_equal(r["probability"], np.ones(64))
    expected = np.where((wi[:, 2] > 0.0)[:, None], 0.5 * 0.6 / np.pi, 0.0) * np.ones(3)
    np.testing.assert_allclose(r["f"], expected, rtol=1e-15, atol=0.0)


def test_register_names_what_a_module_lacks():
    import types

    before = list(lobes.REGISTRY)
    with pytest.raises(TypeError, match="module: lobe 'half'.*eval.*score"):
        lobes.register(types.SimpleNamespace(NAME="half", LAYER=ON_TOP))
    assert lobes.REGISTRY == before


def test_each_verb_dispatches_to_its_lobe_module():
    """The generated dispatch of every verb calls row k's own function (checked from Python
    through the kernels' twins)."""
    layer_value = {UNDER_SPECULAR: 2.0, UNDER_COAT: 3.0, UNDER_FUZZ: 5.0, ON_TOP: 1.0}
    for k, module in enumerate(sk.LOBES):
        assert sk.LOBE_NAMES[k] == module.NAME
        assert sk.layer_factor(k, 2.0, 3.0, 5.0) == layer_value[module.LAYER]
        for dmodel in (D_EON, D_QON):
            assert sk.sampler_of(k, dmodel) == module.sampler.py_func(dmodel)
    assert len(sk.LOBES) == sk.N_LOBES == len(set(sk.LOBE_NAMES))


def test_the_engine_has_no_dispatch_written_by_hand():
    """No ``if k == <lobe>`` chain on a lobe id in the engine's modules: dispatch is generated
    from the registry (``lobes.dispatch``)."""
    import ast

    names = {"DIFFUSE", "SPECULAR", "METAL", "TRANSMISSION", "SUBSURFACE", "SUBSURFACE_T", "COAT", "FUZZ"}
    for mod in ("_surface_kernels", "_surface_passes", "_surface_drivers"):
        tree = ast.parse((ROOT / "openpbr_diffuse" / "nodes" / f"{mod}.py").read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare) and isinstance(node.left, ast.Name) and node.left.id == "k":
                rhs = node.comparators[0]
                assert not (isinstance(rhs, ast.Name) and rhs.id in names), f"{mod}: line {node.lineno}"


def test_the_runners_close_over_the_registry_key():
    """Every runner's closure holds the registry's key, so numba's cache never serves a runner
    compiled for another registry."""
    for builds in sd.BUILDS.values():
        cells = dict(zip(builds.one.py_func.__code__.co_freevars, builds.one.py_func.__closure__))
        assert cells["registry"].cell_contents == sd.REGISTRY_KEY


# ----------------------------------------------------------------------------- inputs
def test_the_inputs_are_declared_once():
    defs = nodedef_inputs(surface_inputs.NODEDEF)
    assert set(MODELLED) == {name for name, _, _ in surface_inputs.MODELLING}
    assert set(MODELLED) <= set(defs)
    width = {"float": 1, "boolean": 1, "color3": 3}
    for name, w in sk.RAW:
        assert w == width[defs[name].type], name
    packed = {name for name, how, _ in surface_inputs.MODELLING if how == surface_inputs.PACKED}
    assert {name for name, _ in sk.RAW} == packed


def test_transmission_depth_is_modelled_without_a_warning():
    """transmission_depth > 0 switches the transmission tint off (the reference graph): it has
    an effect, so setting it warns of nothing."""
    wo = np.array([0.6, 0.0, 0.8])
    tinted = dict(transmission_weight=1.0, transmission_color=(0.2, 0.4, 0.8))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        deep = OpenPBRSurface(**tinted, transmission_depth=1.0)
    assert deep.ignored_inputs == {}
    lobe = {x.name: x for x in deep.lobes(wo)}["transmission"]
    np.testing.assert_array_equal(lobe.albedo, [1.0, 1.0, 1.0])
    lobe = {x.name: x for x in OpenPBRSurface(**tinted).lobes(wo)}["transmission"]
    np.testing.assert_array_equal(lobe.albedo, [0.2, 0.4, 0.8])
    with pytest.warns(IgnoredInputWarning, match="thin_film_weight"):
        OpenPBRSurface(thin_film_weight=0.5)


def test_a_lobe_input_must_be_an_unmodelled_input():
    with pytest.raises(ValueError, match="lobe_inputs: 'base_color'"):
        surface_inputs.packed_inputs(("base_color",))
    with pytest.raises(ValueError, match="lobe_inputs: 'nonsense'"):
        surface_inputs.packed_inputs(("nonsense",))


def test_the_toy_source_is_a_complete_lobe():
    """The toy lobe of the registry test declares everything ``register`` asks for."""
    namespace = {}
    exec(textwrap.dedent(TOY), namespace)
    assert [n for n in lobes.DECLARES if n not in namespace] == []
