"""``openpbr-diffuse explore``: the offline lobe explorer, run in headless Chromium (SwiftShader
WebGL2).  The reference is the library's ``evaluate`` at directions computed here from the
page's stated geometry (sphere pixel -> normal, light from (theta_i, phi)), not by the page."""

import subprocess
import sys

import numpy as np
import pytest
from _browser import opened_page

import openpbr_diffuse as od
from openpbr_diffuse.export import export_text
from openpbr_diffuse.export.explorer import explorer_html, write_explorer

#: Chromium flags: headless, and WebGL2 on the CPU (SwiftShader through ANGLE)
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
#: float32 on SwiftShader (its acos, pow, sin and cos within a few ulp): 5x the float bound of the GLSL export
REL, ABS = 1e-4, 5e-6


def test_page_is_one_offline_file_holding_the_glsl_export_verbatim():
    page = explorer_html()
    assert export_text("glsl").strip() in page
    for remote in ("http://", "https://", "src=", "<link", "@import", "url("):
        assert remote not in page, remote


def test_cli_writes_and_refuses_to_overwrite(tmp_path):
    out = tmp_path / "eon.html"
    run = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "explore", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0 and out.read_text() == explorer_html()
    out.write_text("mine")
    run = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "explore", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1 and out.read_text() == "mine"


def _frame(n):
    """The page's frame at normal n for the view v = +z: X = v's component normal to n."""
    v = np.array([0.0, 0.0, 1.0])
    t = v - (v @ n) * n
    X = t / np.linalg.norm(t) if np.linalg.norm(t) > 1e-6 else np.array([1.0, 0.0, 0.0])
    return np.array([X, np.cross(n, X), n])


@pytest.fixture(scope="module")
def page_values(tmp_path_factory):
    path = write_explorer(tmp_path_factory.mktemp("explore") / "eon.html")
    settings = {"r": 0.7, "rho_r": 0.9, "rho_g": 0.5, "rho_b": 0.1, "theta_o": 50, "theta_i": 60, "phi": 120}
    with opened_page(path, flags=FLAGS) as (page, errors):
        state = page.evaluate("v => window.explorer.set(v)", settings)
        size = page.evaluate("window.explorer.size")
        f = np.array(page.evaluate("window.explorer.readF()"), dtype=np.float64)
        lobe = np.array(page.evaluate("window.explorer.readLobe()"), dtype=np.float64)
        shown = page.evaluate("document.getElementById('error').textContent")
    return {"settings": settings, "state": state, "size": size, "f": f, "lobe": lobe, "errors": errors, "shown": shown}


def test_page_runs_without_errors(page_values):
    assert page_values["errors"] == [] and page_values["shown"] == ""
    assert page_values["state"]["r"] == pytest.approx(0.7)


def test_sphere_pixels_equal_the_library_within_float32(page_values):
    s, size = page_values["settings"], page_values["size"]
    img = page_values["f"].reshape(size, 3 * size, 4)[:, :, :3]  # rows from the bottom (gl_FragCoord)
    ti, ph = np.radians(s["theta_i"]), np.radians(s["phi"])
    light = np.array([np.sin(ti) * np.cos(ph), np.sin(ti) * np.sin(ph), np.cos(ti)])
    rho = np.array([s["rho_r"], s["rho_g"], s["rho_b"]])
    rng = np.random.default_rng(3)
    checked = 0
    for px, py in rng.integers(0, size, (400, 2)):
        p = (np.array([px, py]) + 0.5) / size * 2 - 1
        if p @ p >= 0.98:  # the rim: a pixel's float32 normal decides coverage
            continue
        n = np.array([p[0], p[1], np.sqrt(1 - p @ p)])
        F = _frame(n)
        wi, wo = (F @ light)[None], (F @ np.array([0.0, 0.0, 1.0]))[None]
        wi /= np.linalg.norm(wi)
        if abs(wi[0, 2]) < 1e-3:  # the terminator: the sign of mu_i in float32
            continue
        for m, want in enumerate(
            (
                od.evaluate("eon", wi, wo, s["r"], rho)[0],
                od.evaluate("lambert", wi, wo, s["r"], rho)[0],
                od.evaluate("qon", wi, wo, s["r"], rho)[0],
            )
        ):
            got = img[py, m * size + px]
            assert np.all(np.abs(got - want) <= ABS + REL * np.abs(want)), (m, px, py, got, want)
        checked += 1
    assert checked > 100


def test_polar_plot_values_equal_the_library(page_values):
    s = page_values["settings"]
    lobe = page_values["lobe"].reshape(3, 181, 4)[:, :, :3]
    sn = np.linspace(-1, 1, 181)  # the page's sampling: wi = (s, 0, sqrt(1 - s^2))
    wi = np.stack([sn, np.zeros_like(sn), np.sqrt(1 - sn**2)], axis=1)
    to = np.radians(s["theta_o"])
    wo = np.tile([np.sin(to), 0.0, np.cos(to)], (181, 1))
    rho = [s["rho_r"], s["rho_g"], s["rho_b"]]
    inside = np.abs(sn) < 1  # the two ends are the horizon: f mu_i = 0
    for m, model in enumerate(("eon", "lambert", "qon")):
        want = od.evaluate(model, wi[inside], wo[inside], s["r"], rho) * wi[inside, 2:3]
        got = lobe[m][inside]
        assert np.all(np.abs(got - want) <= ABS + REL * np.abs(want)), model
    assert np.all(lobe[:, ~inside] == 0)
