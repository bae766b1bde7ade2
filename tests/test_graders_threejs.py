"""three.js (npm three) and three-gpu-pathtracer (npm): their EON code graded from the packages.

The verdicts and diagnoses are asserted as measured, and each is checked against an independent
reading: the library's own model functions (``evaluate``, ``eon_terms``, ``od.pdf``) for what the
harness feeds the code, never the packages' shader text; the Lambert limit is computed by hand.
"""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _system import need

import openpbr_diffuse as od
from openpbr_diffuse.conformance.vectors import default_vectors
from openpbr_diffuse.graders import load, threejs, threejs_pathtracer
from openpbr_diffuse.graders.errors import GraderUnavailable
from openpbr_diffuse.graders.grading import grade_subject
from openpbr_diffuse.models import directional_albedo, evaluate
from openpbr_diffuse.models.eon import eon_terms, rho_ms

REL, ABS = threejs.TOLERANCE


def _rows(model="eon"):
    v = default_vectors()
    return v.subset((v.kind == "brdf") & (v.model == model) & (v.wo[:, 2] > 0))


def _within(out, pred, rel=REL, ab=ABS):
    """max |out - pred| / (ab + rel |pred|): <= 1 means every value within the tolerance."""
    return float(np.max(np.abs(out - pred) / (ab + rel * np.abs(pred))))


@pytest.mark.parametrize("name", ["threejs", "three-gpu-pathtracer"])
def test_missing_package_names_the_npm_install(name, tmp_path, monkeypatch):
    monkeypatch.setenv("OPENPBR_DIFFUSE_NPM_CACHE", str(tmp_path))
    with pytest.raises(GraderUnavailable, match="npm install --prefix") as info:
        load(name)
    assert "\n" not in str(info.value) and str(tmp_path) in str(info.value)


def test_cli_missing_package_is_one_line_exit_2(tmp_path):
    env = {"OPENPBR_DIFFUSE_NPM_CACHE": str(tmp_path), "PATH": "/usr/bin:/bin"}
    r = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "check", "--implementation", "threejs"],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "npm install" in r.stderr, r.stderr


@pytest.fixture(scope="module")
def three_folder():
    need("threejs")
    return threejs.package_folder()


@pytest.fixture(scope="module")
def tgp_folder():
    need("three-gpu-pathtracer")
    return threejs_pathtracer.package_folder()


def test_code_is_read_from_the_packages_not_the_project(three_folder, tgp_folder):
    assert "vec3 BRDF_EON(" in threejs.source(three_folder)
    assert "fn eonBrdf(" in threejs_pathtracer.wgsl_functions(tgp_folder)
    import openpbr_diffuse

    root = Path(openpbr_diffuse.__file__).parents[1]
    for p in root.rglob("*"):
        if p.suffix in (".glsl", ".wgsl", ".js") and p.is_file() and ".venv" not in p.parts:
            text = p.read_text(errors="ignore")
            assert "BRDF_EON(" not in text and "fn eonBrdf(" not in text, p


def _copy(folder, files, tmp_path, edit):
    """A package folder with ``files`` copied and ``edit(name, text)`` applied to each."""
    out = tmp_path / "pkg"
    for f in ["package.json", *files]:
        (out / f).parent.mkdir(parents=True, exist_ok=True)
        (out / f).write_text(edit(f, (folder / f).read_text()))
    return out


def test_changed_call_site_is_refused(three_folder, tgp_folder, tmp_path):
    """The harness replays the renderers' statements: a chunk/material without them is refused."""
    chunk = [str(p.relative_to(three_folder)) for p in threejs.chunk_files(three_folder)]
    moved = _copy(
        three_folder,
        chunk,
        tmp_path / "a",
        lambda f, t: t.replace("vec3 irradiance = dotNL *", "vec3 irradiance = 2.0 *"),
    )
    need("node")
    with pytest.raises(GraderUnavailable, match="no longer holds 'vec3 irradiance = dotNL"):
        threejs.source(moved)
    files = [threejs_pathtracer.MODULE, threejs_pathtracer.MATERIAL]
    moved = _copy(
        tgp_folder,
        files,
        tmp_path / "b",
        lambda f, t: t.replace("diffuseBrdf = eonBrdfFunc", "diffuseBrdf = fonBrdfFunc"),
    )
    with pytest.raises(GraderUnavailable, match="no longer holds 'diffuseBrdf = eonBrdfFunc"):
        threejs_pathtracer.wgsl_functions(moved)


@pytest.fixture(scope="module")
def three_graded(three_folder):
    need("gl")
    s = threejs.subject(three_folder)
    return s, {q.quantity: q for q in grade_subject(s, quantities=("brdf", "albedo")).quantities}


def test_threejs_verdicts(three_graded):
    """As eon: fails, the Eq. 14 fit diagnosed (max 2.0e-4); as eon_approx: conforms (max 2.7e-5);
    EON_DirectionalAlbedo conforms as eon (max 9.5e-5, within 5e-5 + 1e-4 |ref|)."""
    s, q = three_graded
    assert set(q) == {"brdf as eon", "albedo as eon", "brdf as eon_approx"}
    g = q["brdf as eon"]
    assert not g.passed and g.diagnosis == "eq14_fit_for_exact" and 1.5e-4 < g.max_abs_error < 3e-4
    assert g.excluded == 24  # mu_o <= 0: the viewer's side only
    g = q["brdf as eon_approx"]
    assert g.passed and g.max_abs_error < 4e-5
    g = q["albedo as eon"]
    assert g.passed and g.max_abs_error < 1.2e-4


def test_threejs_values_against_the_models(three_graded):
    """f = eon_approx above the horizon and 0 below (the saturate(N.L) factor); albedo = EON's."""
    s, _ = three_graded
    rows = _rows()
    f = s.brdf(rows.wi, rows.wo, rows.roughness, rows.rho)
    above = rows.wi[:, 2] > 0
    assert _within(f[above], evaluate("eon_approx", rows.wi, rows.wo, rows.roughness, rows.rho)[above]) <= 1.0
    assert (~above).sum() > 0 and np.all(f[~above] == 0.0)
    mu = np.array([0.05, 0.3, 0.7, 1.0])
    r = np.array([0.0, 0.5, 1.0, 0.8])
    rho = np.array([[0.9, 0.5, 0.1]] * 4)
    got = s.albedo(mu, r, rho)
    assert _within(got, directional_albedo("eon", mu, r, rho)) <= 1.0
    assert np.allclose(got[0], rho[0], atol=1e-6)  # roughness 0: rho, by hand


def test_threejs_bare_function_is_not_zero_below_the_horizon(three_folder):
    """BRDF_EON alone at mu_i < 0 is the lobe at N.L = 0 with s = L.V: rho g + rho_ms h (eon_terms)."""
    need("gl")
    wi = np.array([[0.8, 0.0, -0.6], [0.0, 0.6, -0.8]])
    wo = np.array([[0.6, 0.0, 0.8], [0.0, 0.8, 0.6]])
    r = np.array([0.5, 1.0])
    rho = np.array([[0.8, 0.5, 0.2], [0.3, 0.3, 0.3]])
    bare = threejs.function_values(wi, wo, r, rho, three_folder)
    pred = np.empty_like(rho)
    for k in range(2):
        g, h, avg = eon_terms(0.0, wo[k, 2], float(wi[k] @ wo[k]), r[k], True)
        pred[k] = rho[k] * g + np.array([rho_ms(x, avg) for x in rho[k]]) * h
    assert np.all(bare > 0.01) and _within(bare, pred) <= 1.0


@pytest.fixture(scope="module")
def tgp_graded(tgp_folder):
    need("vulkan")
    s = threejs_pathtracer.subject(tgp_folder)
    return s, {q.quantity: q for q in grade_subject(s, quick=True).quantities}


def test_pathtracer_verdicts(tgp_graded):
    """eonBrdf: fails as eon (Eq. 14 fit, max 2.0e-4), conforms as eon_approx (2.1e-5); fonBrdf
    conforms as fon (2.1e-5); the sampler's pdf integrates to 1 (8e-6) and its samples follow it."""
    s, q = tgp_graded
    g = q["brdf eonBrdf as eon"]
    assert not g.passed and g.diagnosis == "eq14_fit_for_exact" and 1.5e-4 < g.max_abs_error < 3e-4
    assert q["brdf eonBrdf as eon_approx"].passed and q["brdf eonBrdf as eon_approx"].max_abs_error < 4e-5
    assert q["brdf fonBrdf"].passed and q["brdf fonBrdf"].max_abs_error < 4e-5
    pdf, chi = q["sampler pdf eonBrdf as eon"], q["sampler chi2 eonBrdf as eon"]
    assert pdf.passed and pdf.max_abs_error < 1e-4
    ref = pdf.checks[1]["by_strategy"]
    assert ref["eon"] < 2e-3 and min(ref, key=ref.get) == "eon"
    assert chi.passed and chi.checks[1]["status"] == "pass"


def test_pathtracer_values_against_the_models(tgp_graded):
    s, _ = tgp_graded
    paths = dict(s.paths)
    rows = _rows()
    above = rows.wi[:, 2] > 0
    for label, model in (("eonBrdf as eon_approx", "eon_approx"), ("fonBrdf", "fon")):
        f = paths[label].brdf(rows.wi, rows.wo, rows.roughness, rows.rho)
        assert _within(f[above], evaluate(model, rows.wi, rows.wo, rows.roughness, rows.rho)[above]) <= 1.0
        assert np.all(f[~above] == 0.0)
    # the pdf against the reference EON strategy (CLTC + uniform), relative to max(ref, 0.01)
    rng = np.random.default_rng(3)
    wo = od.sample_rng("cosine", np.array([0.0, 0.0, 1.0]), 0.0, 5, shape=(500,))[0]
    wi = od.sample_rng("uniform", np.array([0.0, 0.0, 1.0]), 0.0, 6, shape=(500,))[0]
    r = rng.random(500)
    got = s.pdf(wo, wi, r)
    ref = od.pdf("eon", wo, wi, r)
    assert np.max(np.abs(got - ref) / np.maximum(ref, 1e-2)) < 2e-3


@pytest.mark.slow
def test_cli_end_to_end(three_folder, tgp_folder):
    """``check --implementation``: the Eq. 14 fit where exact EON is claimed conforms with
    warnings (exit 0), the deviation named."""
    need("gl", "vulkan")
    for name in ("threejs", "three-gpu-pathtracer"):
        r = subprocess.run(
            [sys.executable, "-m", "openpbr_diffuse", "check", "--implementation", name, "--json"],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert r.returncode == 0, r.stderr
        d = json.loads(r.stdout)
        assert d["model"] == "eon" and d["tier"] == "conforms with warnings"
        failed = [q for q in d["quantities"] if not q["passed"]]
        assert [q["diagnosis"] for q in failed] == ["eq14_fit_for_exact"]


@pytest.mark.parametrize("module", [threejs, threejs_pathtracer])
def test_docstring_examples(module, three_folder, tgp_folder):
    """The modules' Examples run as written (they read the installed packages)."""
    import doctest

    need("gl", "vulkan")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
