"""Report section "colorshift": builds, its checks pass, images are written, data only."""

import pytest


@pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
def test_colorshift_section_quick(tmp_path):
    from openpbr_diffuse.report.model import Context, SectionResult
    from openpbr_diffuse.report.sections import colorshift

    messages = []
    res = colorshift.build(Context(image_dir=tmp_path, quick=True, progress=messages.append))
    assert isinstance(res, SectionResult) and res.key == "colorshift" and res.title == colorshift.TITLE
    assert len(res.checks) >= 9 and all(c.passed for c in res.checks), [c.to_dict() for c in res.checks if not c.passed]
    assert messages
    for fig in res.figures:
        assert fig.file.startswith("colorshift_") and (tmp_path / fig.file).stat().st_size > 1000
    summary = res.tables[0]
    assert any(row[3] == "cyan" for row in summary.rows)  # the r = 1 headline names patches
    assert [row[0] for row in res.tables[2].rows] == ["Mallett 2019", "Otsu 2018"]
    assert not any("<" in str(cell) for t in res.tables for row in t.rows for cell in row)
