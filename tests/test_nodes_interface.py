"""The shading nodes' interfaces against the MaterialX data library.

The library is read here with the MaterialX Python API directly (not through
``openpbr_diffuse.nodes.materialx_defs``), so a mistake in the project's reader -- names,
types, parsing of default strings, ordering -- shows up as a difference.
"""

import inspect
import json
import sys
import warnings

import MaterialX as mx
import numpy as np
import pytest

from openpbr_diffuse.nodes import IgnoredInputWarning, OpenPBRSurface, OrenNayarDiffuseBSDF, materialx_defs


@pytest.fixture(scope="module")
def library():
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib


def _mx_default(inp):
    """Default of a MaterialX input as a plain Python value, via the MaterialX value API."""
    v = inp.getValue()
    if v is None:
        return None
    if isinstance(v, (bool, int, float, str)):
        return v
    return tuple(float(c) for c in v.asTuple())


def _mx_inputs(library, name):
    return {i.getName(): i for i in library.getNodeDef(name).getActiveInputs()}


def _same(a, b):
    if isinstance(a, tuple) or isinstance(b, tuple):
        return len(a) == len(b) and np.allclose(a, b, rtol=1e-6, atol=0.0)
    if isinstance(a, float) or isinstance(b, float):
        return np.isclose(a, b, rtol=1e-6, atol=0.0)  # MaterialX stores float32
    return a == b


# ----------------------------------------------------------------------------- names, types, defaults
class TestOrenNayarInterface:
    NODEDEF = "ND_oren_nayar_diffuse_bsdf"

    def test_parameters_are_the_nodedef_inputs(self, library):
        params = inspect.signature(OrenNayarDiffuseBSDF).parameters
        assert set(params) == set(_mx_inputs(library, self.NODEDEF))

    def test_defaults_equal_the_library(self, library):
        params = inspect.signature(OrenNayarDiffuseBSDF).parameters
        for name, inp in _mx_inputs(library, self.NODEDEF).items():
            want = _mx_default(inp)
            assert _same(params[name].default, want), (name, params[name].default, want)

    def test_the_spec_values(self):
        # spec/ecosystem.md: weight 1.0, color 0.18 grey, roughness 0.0, normal = Nworld, ec false
        node = OrenNayarDiffuseBSDF()
        assert float(node.weight) == 1.0 and node.color.tolist() == [0.18, 0.18, 0.18]
        assert float(node.roughness) == 0.0 and node.energy_compensation is False
        assert node.normal is None and node.model == "qon"

    def test_types(self, library):
        defs = materialx_defs.nodedef_inputs(self.NODEDEF)
        for name, inp in _mx_inputs(library, self.NODEDEF).items():
            assert defs[name].type == inp.getType()
            assert defs[name].defaultgeomprop == inp.getDefaultGeomPropString()
            assert defs[name].uniform == (inp.getAttribute("uniform") == "true")
        assert defs["energy_compensation"].uniform and defs["normal"].defaultgeomprop == "Nworld"

    def test_api_md_positional_order(self):
        # api.md: OrenNayarDiffuseBSDF(weight, color, roughness, energy_compensation); normal keyword
        node = OrenNayarDiffuseBSDF(0.5, (0.2, 0.3, 0.4), 0.7, True)
        assert float(node.weight) == 0.5 and node.model == "eon" and float(node.roughness) == 0.7
        kinds = {n: p.kind for n, p in inspect.signature(OrenNayarDiffuseBSDF).parameters.items()}
        assert kinds["normal"] == inspect.Parameter.KEYWORD_ONLY


class TestOpenPBRInterface:
    NODEDEF = "ND_open_pbr_surface_surfaceshader"

    def test_every_input_is_accepted_with_the_library_default(self, library):
        params = inspect.signature(OpenPBRSurface).parameters
        for name, inp in _mx_inputs(library, self.NODEDEF).items():
            assert name in params, name
            assert params[name].kind == inspect.Parameter.KEYWORD_ONLY
            assert _same(params[name].default, _mx_default(inp)), name

    def test_defaults_method(self, library):
        d = OpenPBRSurface.defaults()
        lib = _mx_inputs(library, self.NODEDEF)
        assert list(d) == list(lib)  # library order
        assert all(_same(d[n], _mx_default(i)) for n, i in lib.items())
        # a few values stated in spec/ecosystem.md
        assert d["base_color"] == (0.8, 0.8, 0.8) and d["specular_roughness"] == 0.3
        assert d["specular_ior"] == 1.5 and d["geometry_thin_walled"] is False

    def test_options_are_not_inputs(self, library):
        lib = _mx_inputs(library, self.NODEDEF)
        extra = set(inspect.signature(OpenPBRSurface).parameters) - set(lib)
        assert extra == {"selection", "specular_sampling", "multiscatter", "diffuse_model"}

    def test_default_surface_uses_library_values(self):
        s = OpenPBRSurface()
        assert s.inputs["base_color"].tolist() == [0.8, 0.8, 0.8]
        assert float(s.inputs["specular_ior"]) == 1.5
        assert s.ignored_inputs == {}


# ----------------------------------------------------------------------------- the snapshot fallback
class TestSnapshot:
    def test_snapshot_equals_the_installed_library(self, library):
        with open(materialx_defs.SNAPSHOT_FILE) as fh:
            snap = json.load(fh)
        assert snap["source"].startswith("MaterialX") and "make_nodedef_snapshot" in snap["command"]
        for nd in materialx_defs.NODEDEFS:
            lib = _mx_inputs(library, nd)
            recs = snap["nodedefs"][nd]["inputs"]
            assert [r["name"] for r in recs] == list(lib)
            for r in recs:
                inp = lib[r["name"]]
                assert (r["type"], r["value"]) == (inp.getType(), inp.getValueString())

    def test_nodes_work_without_materialx(self, monkeypatch):
        auto = materialx_defs.nodedef_inputs("ND_open_pbr_surface_surfaceshader")
        materialx_defs._records.cache_clear()
        monkeypatch.setitem(sys.modules, "MaterialX", None)  # import MaterialX -> ImportError
        try:
            assert materialx_defs.nodedef_source().startswith("snapshot")
            assert materialx_defs.nodedef_inputs("ND_open_pbr_surface_surfaceshader") == auto
            s = OpenPBRSurface(base_color=(0.5, 0.5, 0.5))
            assert s.albedo(np.array([0.0, 0.0, 1.0])).shape == (3,)
            assert inspect.signature(OrenNayarDiffuseBSDF).parameters["color"].default == (0.18, 0.18, 0.18)
        finally:
            materialx_defs._records.cache_clear()


# ----------------------------------------------------------------------------- bad input
class TestBadInput:
    def test_unknown_input_names_raise_naming_them(self):
        with pytest.raises(ValueError, match="coat_wieght"):
            OpenPBRSurface(coat_wieght=1.0)
        with pytest.raises(ValueError, match="colour"):
            OrenNayarDiffuseBSDF(colour=(1.0, 1.0, 1.0))

    @pytest.mark.parametrize(
        "kwargs, name",
        [
            (dict(base_color=(1.2, 0.5, 0.5)), "base_color"),
            (dict(base_metalness=-0.1), "base_metalness"),
            (dict(specular_roughness=np.nan), "specular_roughness"),
            (dict(base_color=(0.5, 0.5)), "base_color"),
            (dict(specular_weight=-1.0), "specular_weight"),
            (dict(geometry_normal=(0.0, 0.0, 2.0)), "geometry_normal"),
        ],
    )
    def test_surface_values(self, kwargs, name):
        with pytest.raises(ValueError, match=name):
            OpenPBRSurface(**kwargs)

    def test_node_values(self):
        with pytest.raises(ValueError, match="roughness"):
            OrenNayarDiffuseBSDF(roughness=1.5, energy_compensation=True)  # EON r in [0, 1]
        with pytest.raises(ValueError, match="roughness"):
            OrenNayarDiffuseBSDF(roughness=2.0)  # QON sigma <= pi/2
        with pytest.raises(ValueError, match="weight"):
            OrenNayarDiffuseBSDF(weight=2.0)
        with pytest.raises(ValueError, match="color"):
            OrenNayarDiffuseBSDF(color=(0.5, 1.5, 0.5))
        with pytest.raises(TypeError, match="energy_compensation"):
            OrenNayarDiffuseBSDF(energy_compensation=1)
        with pytest.raises(TypeError, match="base_weight"):
            OpenPBRSurface(base_weight="heavy")

    def test_options(self):
        with pytest.raises(ValueError, match="selection"):
            OpenPBRSurface(selection="luminance")
        with pytest.raises(ValueError, match="specular_sampling"):
            OpenPBRSurface(specular_sampling="beckmann")

    def test_directions_and_u(self):
        s = OpenPBRSurface()
        with pytest.raises(ValueError, match="wo"):
            s.albedo(np.array([0.0, 0.0, 0.5]))
        with pytest.raises(ValueError, match="u"):
            s.sample(np.array([0.0, 0.0, 1.0]), np.array([0.5, 1.0]))
        with pytest.raises(ValueError, match="u"):
            s.sample(np.array([0.0, 0.0, 1.0]), np.array([0.5, 0.5, 0.5, 0.5]))


# ----------------------------------------------------------------------------- ignored inputs
class TestIgnoredInputs:
    def test_reported_and_warned(self):
        # coat, fuzz, transmission, subsurface are modelled; thin film and emission are not
        with pytest.warns(
            IgnoredInputWarning, match="thin_film_weight.*emission_color|emission_color.*thin_film_weight"
        ):
            s = OpenPBRSurface(
                thin_film_weight=0.5, emission_color=(1.0, 0.0, 0.0), base_metalness=0.2, coat_weight=0.5
            )
        assert set(s.ignored_inputs) == {"thin_film_weight", "emission_color"}

    def test_defaults_given_explicitly_are_not_reported(self):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            s = OpenPBRSurface(coat_weight=0.0, transmission_color=(1.0, 1.0, 1.0), geometry_normal=(0.0, 0.0, 1.0))
        assert s.ignored_inputs == {}

    def test_geomprops_count_when_given(self):
        with pytest.warns(IgnoredInputWarning, match="geometry_tangent"):
            s = OpenPBRSurface(geometry_tangent=(1.0, 0.0, 0.0))
        assert list(s.ignored_inputs) == ["geometry_tangent"]

    def test_ignored_inputs_change_nothing(self):
        wo = np.array([0.6, 0.0, 0.8])
        wi = np.array([-0.3, 0.1, np.sqrt(0.9)])
        with pytest.warns(IgnoredInputWarning):
            s = OpenPBRSurface(thin_film_weight=1.0, specular_roughness_anisotropy=0.5, emission_luminance=10.0)
        ref = OpenPBRSurface()
        assert np.array_equal(s.eval(wi, wo), ref.eval(wi, wo))
        assert np.array_equal(s.albedo(wo), ref.albedo(wo))

    def test_ior_below_one_warns(self):
        with pytest.warns(UserWarning, match="specular_ior < 1"):
            s = OpenPBRSurface(specular_ior=1.0 / 1.5)
        # the reciprocal index has the same F0: same lobe as ior 1.5
        ref = OpenPBRSurface(specular_ior=1.5)
        wo = np.array([0.6, 0.0, 0.8])
        assert np.allclose(s.albedo(wo), ref.albedo(wo), rtol=1e-12)
