"""The report section "materials": the contract of report/model.py, its images, its checks."""

import shutil

from openpbr_diffuse.readers import BUNDLED_MATERIALS
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
    res = materials.build(Context(image_dir=images, paths=[src], quick=True))
    assert isinstance(res, SectionResult) and res.key == "materials" and res.title == materials.TITLE
    summary = res.tables[0]
    assert len(summary.rows) == 4 and len(summary.columns) == len(summary.rows[0])
    row = {r[1]: r for r in summary.rows}
    assert row["G_mat"][2] == "ND_disney_principled" and "maps onto no node" in row["G_mat"][9]
    assert any("broken.mtlx" in w for w in res.warnings)
    files = {f.file for f in res.figures}
    assert "materials_albedo.png" in files and sum(f.endswith("_render.png") for f in files) == 3
    for f in files:
        assert (images / f).is_file() and f.startswith("materials_")
    # the unreadable file is a failed check, never a pass; the materials' own checks pass
    read = next(c for c in res.checks if c.name == "every given material file is read")
    assert not read.passed and read.measured == 1 and "broken.mtlx" in read.detail
    assert all(c.passed for c in res.checks if c is not read)
    # per-material parameter tables carry the provenance
    clay = next(t for t in res.tables if t.caption.startswith("clay_rough"))
    assert any(r[0] == "base_diffuse_roughness" and "authored" in r[3] for r in clay.rows)


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
    res = materials.build(Context(image_dir=images, paths=[src], quick=True))
    ev = next(c for c in res.checks if c.name == "every material found is evaluated")
    assert not ev.passed and ev.measured == 1 and "Bad" in ev.detail and "gamma99" in ev.detail
    rows = {r[1]: r for r in res.tables[0].rows}
    assert set(rows) == {"Bad", "Good"} and "gamma99" in rows["Bad"][9]
    assert sum(f.file.endswith("_render.png") for f in res.figures) == 1
