"""The shipped simulation tables: checked against the independent single-bounce quadrature,
the white furnace, and a re-grading from the tables; the report section builds from them."""

import numpy as np
import pytest
from _vgroove_quad import single_bounce_albedo

from openpbr_diffuse.simulation import grading as gr


@pytest.fixture(scope="module")
def albedo():
    header, cols = gr.load("albedo")
    for key in ("title", "method", "resolution", "error", "library", "regenerate"):
        assert key in header
    assert "tools/make_simulation_tables.py" in header["regenerate"]
    return cols


def test_shipped_single_bounce_matches_quadrature(albedo):
    sel = (albedo["geometry"] == "vcavity") & (albedo["kind"] == "directional") & np.isclose(albedo["rho"], 1.0)
    z = []
    for k in np.flatnonzero(sel):
        expected, _ = single_bounce_albedo(albedo["mu"][k], albedo["roughness"][k], n_phi=256, n_u=16)
        z.append((albedo["E1"][k] - expected) / albedo["E1_se"][k])
    z = np.array(z)
    assert len(z) >= 40
    assert np.max(np.abs(z)) < 4.5 and 0.6 < np.std(z) < 1.4


def test_shipped_white_furnace_and_orders(albedo):
    one = np.isclose(albedo["rho"], 1.0)
    assert np.allclose(albedo["E"][one], 1.0, atol=1e-9)
    assert np.allclose(albedo["E1"] + albedo["E2"] + albedo["E3"], albedo["E"], atol=3e-9)
    # albedo grows with rho, and the multi-bounce share with roughness
    assert np.all(np.isfinite(albedo["E_se"])) and np.all(albedo["E_se"] >= 0)


def test_regrading_reproduces_the_shipped_grading(albedo):
    _, brdf = gr.load("brdf")
    _, g = gr.load("grading")
    i = int(np.flatnonzero((g["model"] == "eon") & (g["geometry"] == "smith-ggx") & (g["fit"] == "albedo"))[2])
    row = gr.grade_surface("eon", albedo, brdf, "smith-ggx", float(g["roughness"][i]))
    assert row["model_roughness"] == pytest.approx(g["model_roughness"][i], abs=1e-4)
    assert row["albedo_rms"] == pytest.approx(g["albedo_rms"][i], rel=1e-6)
    assert row["brdf_rel_rms"] == pytest.approx(g["brdf_rel_rms"][i], rel=1e-6)


def test_eon_rho_ms_in_the_colorshift_table_is_eq18():
    from openpbr_diffuse.models.fon import E_F_avg

    _, cs = gr.load("colorshift")
    r, rho = cs["r_eon"], cs["rho"]
    avg = np.array([E_F_avg(x) for x in r])
    # Eq. 18 written out here, against the table's EON column
    assert np.allclose(cs["ms_eon"], rho**2 * avg / (1 - rho * (1 - avg)), atol=1e-9)


def test_report_section_builds(tmp_path):
    from openpbr_diffuse.report.model import Context
    from openpbr_diffuse.report.runner import run_section
    from openpbr_diffuse.report.sections import simulation

    res = run_section("simulation", Context(image_dir=tmp_path, quick=True)).result
    assert res.key == "simulation" and res.tables and len(res.figures) == 3
    for f in res.figures:
        assert (tmp_path / f.file).stat().st_size > 1000 and f.file.startswith("simulation_")
    from openpbr_diffuse.report.model import QUICK_NOT_RUN

    ran = [c for c in res.checks if c.status != "not run"]
    assert ran and all(c.passed for c in ran), [(c.name, c.measured) for c in ran if not c.passed]
    live = [c for c in res.checks if c.status == "not run"]  # --quick: the full report runs them
    assert len(live) == 4 and all(c.not_run == QUICK_NOT_RUN for c in live)
    mu, _, _, values, estimate = simulation._live_check(simulation._tables()["albedo"][1], True)
    assert [simulation._live_name(col, mu) for col in values] == [c.name for c in live[:3]]
    for v, s, ref, ref_se in values.values():
        assert abs(v - ref) / np.hypot(s, ref_se) <= 4.5
    assert abs(estimate.albedo[0, 1] - 1.0) <= 1e-12
