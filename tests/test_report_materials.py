"""The report section "materials": the contract of report/model.py, its images, its checks."""

import shutil

import pytest

from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials
from openpbr_diffuse.readers.evaluate import evaluate
from openpbr_diffuse.report.model import Context, SectionResult
from openpbr_diffuse.report.sections import materials


def test_materials_section_on_given_files(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    for name in ("clay_rough.mtlx", "plaster_preview.usda", "cloth_qon.mtlx"):
        shutil.copy(BUNDLED_MATERIALS / name, src / name)
    (src / "broken.mtlx").write_text("<materialx version='1.39'><oops")
    (src / "gltf.mtlx").write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <disney_principled name="G" type="surfaceshader" />
  <surfacematerial name="G_mat" type="material"><input name="surfaceshader" type="surfaceshader" nodename="G" /></surfacematerial>
</materialx>""")
    images = tmp_path / "img"
    images.mkdir()
    ctx = Context(image_dir=images, paths=[src], quick=True)
    res = materials.build(ctx)
    assert isinstance(res, SectionResult) and res.key == "materials" and res.title == materials.TITLE
    # one record per material, and one for the file that could not be read
    records = ctx.extra["materials"]
    row = {r["material"]: r for r in records}
    assert len(records) == 5 and set(row) == {None, "clay_rough", "/Materials/plaster_preview", "cloth_qon", "G_mat"}
    assert row["G_mat"]["shader"] == "ND_disney_principled" and row["G_mat"]["verdict"] == "unsupported"
    assert "maps onto no node" in row["G_mat"]["detail"]
    assert row[None]["relpath"] == "broken.mtlx" and row[None]["verdict"] == "fail"
    counts = dict(map(tuple, res.tables[0].rows))
    assert counts == {"fail": 0, "flagged": 0, "unsupported": 1, "pass": 3, "file not read": 1}
    # the record's numbers are those of the readers' own evaluate()
    (clay,) = load_materials(src / "clay_rough.mtlx")
    ev = evaluate(clay, [30.0], [30.0], [180.0])
    assert row["clay_rough"]["albedo"] == pytest.approx(ev["albedo"][0], abs=1e-12)
    assert row["clay_rough"]["diffuse_probability"] == pytest.approx(ev["diffuse"]["probability"][0], abs=1e-12)
    assert any("broken.mtlx" in w for w in res.warnings)
    files = {f.file for f in res.figures}
    assert "materials_distributions.png" in files
    assert sum(f.endswith("_render.png") for f in files) == 3 and sum(f.endswith("_albedo.png") for f in files) == 3
    for f in files:
        assert (images / f).is_file() and f.startswith("materials_")
    # the unreadable file is a failed check, never a pass; the materials' own checks pass
    read = next(c for c in res.checks if c.name == "every given material file is read")
    assert not read.passed and read.measured == 1 and "broken.mtlx" in read.detail
    assert all(c.passed for c in res.checks if c is not read)
    # the drawn materials' parameter tables carry the provenance
    clay_t = next(t for t in res.tables if "clay_rough" in t.caption and t.caption.endswith("resolved parameters"))
    assert any(r[0] == "base_diffuse_roughness" and "authored" in r[3] for r in clay_t.rows)


def test_materials_section_fails_on_a_material_that_cannot_be_evaluated(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    (src / "two.mtlx").write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <open_pbr_surface name="Sa" type="surfaceshader">
    <input name="base_color" type="color3" value="0.5, 0.5, 0.5" colorspace="gamma99" />
  </open_pbr_surface>
  <surfacematerial name="Bad" type="material"><input name="surfaceshader" type="surfaceshader" nodename="Sa" /></surfacematerial>
  <open_pbr_surface name="Sb" type="surfaceshader" />
  <surfacematerial name="Good" type="material"><input name="surfaceshader" type="surfaceshader" nodename="Sb" /></surfacematerial>
</materialx>""")
    images = tmp_path / "img"
    images.mkdir()
    ctx = Context(image_dir=images, paths=[src], quick=True)
    res = materials.build(ctx)
    ev = next(c for c in res.checks if c.name == "every material found is evaluated")
    assert not ev.passed and ev.measured == 1 and "Bad" in ev.detail and "gamma99" in ev.detail
    rows = {r["material"]: r for r in ctx.extra["materials"]}
    assert set(rows) == {"Bad", "Good"} and "gamma99" in rows["Bad"]["detail"]
    assert rows["Bad"]["verdict"] == "fail" and rows["Bad"]["reasons"] == ["not evaluated"]
    assert sum(f.file.endswith("_render.png") for f in res.figures) == 1
