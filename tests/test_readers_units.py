"""MaterialX ``unit`` / ``unittype``: a value with a unit is converted to the target unit
(the nodedef input's unit, else the unit type's unit of scale 1: meter, degree) before it is
used.  Expected values: closed forms with the scales of the data library's own ``unitdef``
(read here from the library document) -- 75 centimeter = 75 x 0.01 / 1 meter."""

import math
import os
import textwrap
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

SHARED = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or Path(__file__).resolve().parents[1].parent / "shared")
UNIT_FILE = SHARED / "corpus/realworld/MaterialX/resources/Materials/TestSuite/stdlib/units/standard_surface_unit.mtlx"

DOC = """
<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="G">
    <constant name="len" type="float">
      <input name="value" type="float" value="75" unit="centimeter" unittype="distance" />
    </constant>
    <constant name="ang" type="float">
      <input name="value" type="float" value="{angle}" unit="radian" unittype="angle" />
    </constant>
    <divide name="frac" type="float">
      <input name="in1" type="float" nodename="ang" />
      <input name="in2" type="float" value="180" />
    </divide>
    <output name="len_out" type="float" nodename="len" />
    <output name="frac_out" type="float" nodename="frac" />
  </nodegraph>
  <open_pbr_surface name="S" type="surfaceshader">
    <input name="base_weight" type="float" nodegraph="G" output="len_out" />
    <input name="base_diffuse_roughness" type="float" nodegraph="G" output="frac_out" />
    <input name="specular_ior" type="float" value="150" unit="centimeter" unittype="distance" />
    <input name="specular_roughness" type="float" value="{rough}" unit="{rough_unit}" unittype="distance" />
  </open_pbr_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S" />
  </surfacematerial>
  <open_pbr_surface name="S2" type="surfaceshader" />
  <surfacematerial name="Plain" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S2" />
  </surfacematerial>
</materialx>
"""


def _scales():
    """{unit: scale} of the data library's unitdefs (MaterialX's stdlib_defs.mtlx)."""
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return {u.getName(): float(u.getAttribute("scale")) for d in lib.getUnitDefs() for u in d.getUnits()}


def _load(tmp_path, angle=math.pi / 4, rough="250", rough_unit="millimeter"):
    p = tmp_path / "units.mtlx"
    p.write_text(textwrap.dedent(DOC).lstrip().format(angle=angle, rough=rough, rough_unit=rough_unit))
    return {m.name: m for m in load_materials(p)}


def test_distance_and_angle_units_are_converted(tmp_path):
    s = _scales()
    mats = _load(tmp_path)
    m = mats["M"]
    assert m.error == "" and not m.warnings, (m.error, m.warnings)
    p = m.parameters
    # float32 scale factors (MaterialX's converter works in single precision)
    assert p["base_weight"].value == pytest.approx(75 * s["centimeter"] / s["meter"], rel=1e-6)
    assert p["specular_ior"].value == pytest.approx(150 * s["centimeter"] / s["meter"], rel=1e-6)
    assert p["specular_roughness"].value == pytest.approx(250 * s["millimeter"] / s["meter"], rel=1e-6)
    # pi/4 radian = 45 degree (the angle unit of scale 1); / 180 -> 0.25
    assert p["base_diffuse_roughness"].value == pytest.approx(math.pi / 4 * s["radian"] / s["degree"] / 180, rel=1e-6)
    assert p["base_diffuse_roughness"].value == pytest.approx(0.25, rel=1e-6)
    assert "150 centimeter -> 1.5 meter" in p["specular_ior"].provenance
    assert p["specular_ior"].authored == 150.0
    assert mats["Plain"].error == ""


def test_unit_conversion_avoids_false_clamp(tmp_path):
    # 75 cm read as 75 would be clamped to 1 with a warning
    m = _load(tmp_path, rough="90", rough_unit="centimeter")["M"]
    np.testing.assert_allclose(m.node_inputs["specular_roughness"].value, 0.9, rtol=1e-6)
    assert not [w for w in m.warnings if "outside" in w], m.warnings


def test_unknown_unit_fails_its_material_only(tmp_path):
    mats = _load(tmp_path, rough_unit="parsec")
    assert "parsec" in mats["M"].error and not mats["M"].supported
    assert mats["Plain"].error == "" and mats["Plain"].supported


@pytest.mark.corpus
@pytest.mark.skipif(not UNIT_FILE.is_file(), reason="../shared/corpus is absent")
def test_standard_surface_unit_file():
    s = _scales()
    (m,) = load_materials(UNIT_FILE)
    p = m.parameters
    assert p["base"].value == pytest.approx(75 * s["centimeter"], rel=1e-6)
    assert p["specular_IOR"].value == pytest.approx(150 * s["centimeter"], rel=1e-6)
    assert p["specular_roughness"].value == pytest.approx(250 * s["millimeter"], rel=1e-6)
    assert p["subsurface"].value == pytest.approx(400 * s["millimeter"], rel=1e-6)
    assert not [w for w in m.warnings if "outside" in w], m.warnings
