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


def _counting_reads(monkeypatch):
    """Count the calls of ``readers.load_materials`` (every read of a material file)."""
    import openpbr_diffuse.readers as readers

    calls = []
    real = readers.load_materials

    def counted(path, *args, **kwargs):
        calls.append(str(path))
        return real(path, *args, **kwargs)

    monkeypatch.setattr(readers, "load_materials", counted)
    return calls


@pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
def test_colorshift_materials_table_reads_the_files_once_through_the_library_cache(tmp_path, monkeypatch):
    """A second run (a new cache object on the same folder) reads no material file and gives
    the same table and warnings; each row's own-roughness columns equal EON evaluated for that
    material alone."""
    from openpbr_diffuse.library import Cache, LibraryOptions
    from openpbr_diffuse.readers import BUNDLED_MATERIALS, find_material_files
    from openpbr_diffuse.report.model import Context
    from openpbr_diffuse.report.sections import colorshift
    from openpbr_diffuse.spectral import ColourSet, colorimetry, colour_shift, from_materials

    cm = colorimetry("D65", "lin_rec709")
    calls = _counting_reads(monkeypatch)

    def build():
        ctx = Context(image_dir=tmp_path, extra={"library": LibraryOptions(cache=Cache(tmp_path / "cache"))})
        return colorshift._materials_table(ctx, cm)

    (first, w1), n_first = build(), len(calls)
    (again, w2), n_again = build(), len(calls) - n_first
    files = find_material_files([BUNDLED_MATERIALS])
    assert n_first == len(files) and n_again == 0
    assert again.rows == first.rows and w2 == w1 and len(first.rows) >= 10
    # the reference: the materials read directly, each evaluated on its own
    cs, w_direct = from_materials(files, cm)
    assert w_direct == w1 and [row[0] for row in first.rows] == cs.names
    for p, row in enumerate(first.rows):
        r = cs.extra[p]["material_diffuse_roughness"] or 0.0
        own = colour_shift(
            ColourSet(
                [cs.names[p]], cs.spectra[p : p + 1], cs.rho_rgb[p : p + 1], ["m"], cs.roundtrip_delta_e[p : p + 1]
            ),
            [r],
            [1.0],
            cm,
        )
        assert row[4:6] == [
            round(float(own.delta_e_rgb_vs_spectral[0, 0, 0]), 4),
            round(float(own.delta_e_shift[0, 0, 0]), 4),
        ]


@pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
def test_colorshift_materials_table_reads_an_edited_file_again(tmp_path, monkeypatch):
    """The cached colours of a file are not used once the file changes."""
    import os
    import shutil

    from openpbr_diffuse.library import Cache, LibraryOptions
    from openpbr_diffuse.readers import BUNDLED_MATERIALS
    from openpbr_diffuse.report.model import Context
    from openpbr_diffuse.report.sections import colorshift
    from openpbr_diffuse.spectral import colorimetry

    cm = colorimetry("D65", "lin_rec709")
    mat = tmp_path / "in" / "clay.mtlx"
    mat.parent.mkdir()
    shutil.copy(BUNDLED_MATERIALS / "clay_rough.mtlx", mat)
    os.utime(mat, (1e9, 1e9))  # long before the run: cacheable
    calls = _counting_reads(monkeypatch)

    def build():
        ctx = Context(image_dir=tmp_path, paths=[mat], extra={"library": LibraryOptions(cache=Cache(tmp_path / "c"))})
        table, _ = colorshift._materials_table(ctx, cm)
        return table.rows

    before = build()
    assert build() == before and len(calls) == 1
    text = mat.read_text(encoding="utf-8")
    edited = text.replace(
        'name="base_diffuse_roughness" type="float" value="1.0"',
        'name="base_diffuse_roughness" type="float" value="0.25"',
    )
    assert edited != text
    mat.write_text(edited, encoding="utf-8")
    os.utime(mat, (1e9 + 10, 1e9 + 10))
    after = build()
    assert len(calls) == 2 and after[0][3] == 0.25 and before[0][3] == 1.0


@pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
def test_colorshift_materials_table_a_file_that_cannot_be_used_costs_only_its_own_rows(tmp_path, monkeypatch):
    """The colours of all files are upsampled together; when that fails for one file's
    colours, that file alone is left out (its error is its warning) and the others keep theirs."""
    from openpbr_diffuse.readers import BUNDLED_MATERIALS
    from openpbr_diffuse.report.model import Context
    from openpbr_diffuse.report.sections import colorshift
    from openpbr_diffuse.spectral import colorimetry, colorsets

    cm = colorimetry("D65", "lin_rec709")
    ctx = Context(image_dir=tmp_path)
    good, good_warnings = colorshift._materials_table(ctx, cm)
    real = colorsets.from_colour_records

    def refusing(records, *args, **kwargs):
        if any(r["name"] == "clay_rough" for r in records):
            raise ValueError("cannot upsample clay_rough")
        return real(records, *args, **kwargs)

    monkeypatch.setattr(colorsets, "from_colour_records", refusing)
    table, warnings = colorshift._materials_table(ctx, cm)
    assert [row for row in good.rows if row[0] != "clay_rough"] == table.rows
    assert len(table.rows) == len(good.rows) - 1
    assert f"{BUNDLED_MATERIALS / 'clay_rough.mtlx'}: cannot upsample clay_rough" in warnings
    assert [w for w in warnings if "cannot upsample" not in w] == [w for w in good_warnings if "clay_rough" not in w]
