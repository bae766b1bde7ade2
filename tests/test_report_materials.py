"""The report section "materials": the contract of report/model.py, its images, its checks."""
import shutil

import pytest

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
  <gltf_pbr name="G" type="surfaceshader" />
  <surfacematerial name="G_mat" type="material"><input name="surfaceshader" type="surfaceshader" nodename="G" /></surfacematerial>
</materialx>""")
    images = tmp_path / "img"
    images.mkdir()
    res = materials.build(Context(image_dir=images, paths=[src], quick=True))
    assert isinstance(res, SectionResult) and res.key == "materials" and res.title == materials.TITLE
    summary = res.tables[0]
    assert len(summary.rows) == 4 and len(summary.columns) == len(summary.rows[0])
    row = {r[1]: r for r in summary.rows}
    assert row["G_mat"][2] == "ND_gltf_pbr_surfaceshader" and "maps onto no node" in row["G_mat"][9]
    assert any("broken.mtlx" in w for w in res.warnings)
    files = {f.file for f in res.figures}
    assert "materials_albedo.png" in files and sum(f.endswith("_render.png") for f in files) == 3
    for f in files:
        assert (images / f).is_file() and f.startswith("materials_")
    assert res.checks and all(c.passed for c in res.checks)
    # per-material parameter tables carry the provenance
    clay = next(t for t in res.tables if t.caption.startswith("clay_rough"))
    assert any(r[0] == "base_diffuse_roughness" and "authored" in r[3] for r in clay.rows)
