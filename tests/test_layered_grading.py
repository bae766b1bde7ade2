"""The layering rules as the project computes them, the shipped tables and the report section."""

import math

import numpy as np
import pytest

from openpbr_diffuse.approximations import layering_grading as lg
from openpbr_diffuse.report.model import Context
from openpbr_diffuse.simulation.layered import smooth_lambert_albedo


def test_openpbr_rules_are_what_openpbr_surface_computes():
    from openpbr_diffuse.nodes.openpbr_surface import OpenPBRSurface

    mu = np.array([1.0, 0.6, 0.2])
    wo = np.stack([np.sqrt(1 - mu**2), 0 * mu, mu], -1)
    s = OpenPBRSurface(
        base_color=[0.8, 0.5, 0.2],
        specular_ior=1.7,
        specular_roughness=0.4,
        base_diffuse_roughness=0.0,
        diffuse_model="lambert",
    )
    d = next(l for l in s.lobes(wo) if l.name == "diffuse")
    np.testing.assert_allclose(
        d.weight * d.albedo, lg.diffuse_albedo("openpbr", mu[:, None], 1.7, [0.8, 0.5, 0.2], 0.4), rtol=1e-6
    )
    cc = math.exp(-0.3)
    s = OpenPBRSurface(
        base_color=[0.8, 0.5, 0.2],
        specular_weight=0.0,
        coat_weight=1.0,
        coat_ior=1.6,
        coat_roughness=0.5,
        coat_color=[cc] * 3,
        base_diffuse_roughness=0.0,
        diffuse_model="lambert",
    )
    d = next(l for l in s.lobes(wo) if l.name == "diffuse")
    np.testing.assert_allclose(
        d.weight * d.albedo, lg.diffuse_albedo("openpbr_coat", mu[:, None], 1.6, [0.8, 0.5, 0.2], 0.5, 0.3), rtol=1e-6
    )


def test_eon_base_rules_are_what_openpbr_surface_computes():
    from openpbr_diffuse.nodes.openpbr_surface import OpenPBRSurface

    mu = np.array([0.9, 0.3])
    wo = np.stack([np.sqrt(1 - mu**2), 0 * mu, mu], -1)
    s = OpenPBRSurface(base_color=[0.8, 0.5, 0.2], specular_ior=1.5, specular_roughness=0.5, base_diffuse_roughness=0.7)
    d = next(l for l in s.lobes(wo) if l.name == "diffuse")
    ref = lg.eon_base_albedo("openpbr", mu[:, None], 1.5, np.array([0.8, 0.5, 0.2])[None], 0.7, 0.5)
    np.testing.assert_allclose(d.weight * d.albedo, ref, rtol=2e-5)


def test_shipped_eon_rows():
    from openpbr_diffuse._csv import read_headed_csv

    header, names, rows = read_headed_csv(lg.DATA / "layered_grading_eon.csv")
    assert "regenerate" in header and len(rows) == 80
    col = {k: i for i, k in enumerate(names)}
    coat, scal = [], []
    for r in rows:
        phys, se = float(r[col["physics"]]), float(r[col["physics_se"]])
        assert 0 < phys < 1 and 0 < se < 2e-3
        coat.append(abs(float(r[col["openpbr_coat"]]) / phys - 1))
        scal.append(abs(float(r[col["openpbr"]]) / phys - 1))
        if float(r[col["rho"]]) < 1:
            assert float(r[col["openpbr"]]) > phys  # albedo scaling misses the internal reflection
    # the coat rule (with its internal-reflection darkening) is far closer than albedo scaling
    assert max(coat) < 0.3 and np.mean(coat) < np.mean(scal) / 4


def test_shipped_smooth_rows_are_the_closed_form():
    header, rows = lg.load_table()
    assert header["regenerate"] == "python tools/make_layered_tables.py" and "library" in header
    smooth = [r for r in rows if r["interface_alpha"] == 0.0]
    assert len(smooth) == 240
    for r in smooth[::17]:
        exact = float(smooth_lambert_albedo(r["n"], r["rho"], r["mu"], r["tau"])) - r["physics_specular"]
        assert r["physics"] == pytest.approx(exact, abs=1e-9)


def test_shipped_rough_rows_are_physical():
    _, rows = lg.load_table()
    rough = [r for r in rows if r["interface_alpha"] > 0]
    for r in rough:
        assert 0 <= r["physics"] <= 1 and 0 < r["physics_se"] < 2e-3
        if r["rho"] == 1.0 and r["tau"] == 0.0:  # furnace: every path leaves
            assert r["physics"] + r["physics_specular"] == pytest.approx(1.0, abs=1e-9)


def test_rules_limits():
    # index-matched: every rule but the coat's reduces to the base
    for rule in ("openpbr", "reciprocal", "gotanda_1mF0", "gotanda_layered", "weidlich_wilkie"):
        v = lg.diffuse_albedo(rule, np.array([1.0, 0.3]), 1.0, 0.7)
        np.testing.assert_allclose(v, 0.7, atol=2e-3)
    with pytest.raises(ValueError, match="rule"):
        lg.diffuse_albedo("nope", 0.5, 1.5, 0.5)


def test_report_section(tmp_path):
    from openpbr_diffuse.report.sections import SECTIONS, layered

    assert "layered" in SECTIONS
    from openpbr_diffuse.report.model import QUICK_NOT_RUN
    from openpbr_diffuse.report.runner import run_section

    res = run_section("layered", Context(image_dir=tmp_path, quick=True)).result
    # --quick: the live simulations are listed, not run (the full report runs them)
    assert res.checks and all(c.status == "not run" and c.not_run == QUICK_NOT_RUN for c in res.checks)
    assert res.not_run == QUICK_NOT_RUN
    live = layered._live(True, lg.load_table()[1])  # the full report's live checks, 20,000 paths
    assert [c.name for c in live] == [c.name for c in res.checks]
    assert all(c.passed for c in live), [c for c in live if not c.passed]
    assert any("Headline" in n for n in res.notes)
    assert (tmp_path / "layered_grading.png").is_file()
    # the headline number, recomputed from the closed form and OpenPBR's E_spec
    mu = 0.1
    phys = float(smooth_lambert_albedo(1.5, 0.8, mu)) - float(lg.g.fresnel(mu, 1.5))
    head = float(lg.diffuse_albedo("openpbr", mu, 1.5, 0.8)) / phys - 1
    assert f"{100 * head:+.0f} %" in next(n for n in res.notes if "Headline" in n)
