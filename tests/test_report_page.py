"""The report: every section on the page (parsed, and opened in headless Chromium),
report.json's schema, escaping, atomic replacement, exit codes."""

import json
import sys
import types
from html.parser import HTMLParser
from pathlib import Path

import pytest
from _system import CHROMIUM, need

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.report import runner
from openpbr_diffuse.report.model import Check, SectionResult, Table
from openpbr_diffuse.report.sections import SECTIONS

#: every result's fields (openpbr_diffuse.result.Result), then a check's own
CHECK_KEYS = {
    "id",
    "kind",
    "quantity",
    "verdict",
    "tier",
    "finding",
    "worst",
    "status",
    "not_run",
    "section",
    "name",
    "measured",
    "threshold",
    "comparison",
    "expected",
    "unit",
    "reference",
    "detail",
    "passed",
}
SECTION_KEYS = {
    "key",
    "lists",
    "findings",
    "title",
    "status",
    "not_run",
    "elapsed_s",
    "error",
    "notes",
    "warnings",
    "checks",
    "tables",
    "figures",
}


class _Page(HTMLParser):
    """Collects the sections, images and any script element of a page."""

    def __init__(self):
        super().__init__()
        self.sections, self.images, self.scripts, self.text = {}, [], 0, []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "section" and "data-key" in a:
            self.sections[a["data-key"]] = a.get("data-status")
        elif tag == "img":
            self.images.append(a.get("src"))
        elif tag == "script":
            self.scripts += 1

    def handle_data(self, data):
        self.text.append(data)


def parse(path):
    p = _Page()
    p.feed(Path(path).read_text(encoding="utf-8"))
    return p


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("rep") / "report"
    status = main(["report", "--quick", "--out", str(out), "--no-progress"])
    return out, status


def test_quick_report_passes_and_shows_every_section(quick_report):
    out, status = quick_report
    assert status == 0
    page = parse(out / "index.html")
    assert list(page.sections) == list(SECTIONS)  # every section, in order
    mine = ("models", "albedo", "sampling", "implementations", "timings")
    assert all(page.sections[k] == "pass" for k in mine)
    assert all(page.sections[k] in ("pass", "not available", "findings", "not run") for k in SECTIONS)
    assert page.sections["graders"] in ("findings", "not run")  # third-party verdicts are not checks
    assert page.scripts == 1  # the materials table's filter and sort, allowed by its hash (test_library_scale.py)
    assert page.images and all((out / src).is_file() for src in page.images)
    assert {Path(s).name.split("_")[0] for s in page.images} >= set(mine) - {"implementations"}
    assert not list(out.parent.glob(".report.*"))  # no temporary directory left


def test_report_json_schema(quick_report):
    out, _ = quick_report
    doc = json.loads((out / "report.json").read_text())
    assert doc["schema"] == runner.SCHEMA and doc["passed"] is True and doc["quick"] is True
    assert [s["key"] for s in doc["sections"]] == list(SECTIONS)
    assert doc["n_checks"] == len(doc["checks"]) > 40 and doc["n_failed"] == 0
    for s in doc["sections"]:
        assert set(s) == SECTION_KEYS
        for f in s["figures"]:
            assert (out / f["file"]).is_file()
    from openpbr_diffuse.models.registry import INFO
    from openpbr_diffuse.report.model import QUICK_MODELS, QUICK_NOT_RUN, QUICK_STRATEGIES
    from openpbr_diffuse.sampling import STRATEGIES

    for c in doc["checks"]:
        assert set(c) == CHECK_KEYS and c["reference"]
        if c["status"] == "not run":  # the full report runs them
            assert c["not_run"] == QUICK_NOT_RUN and c["passed"] is False
            assert c["section"] in ("simulation", "layered", "models", "albedo", "sampling", "approximations")
        else:
            assert c["passed"] is True and c["status"] == "pass"
    skipped = {c["section"] for c in doc["checks"] if c["status"] == "not run"}
    assert skipped == {"simulation", "layered", "models", "albedo", "sampling", "approximations"}
    assert doc["evidence"]["n_not_run"] == sum(c["status"] == "not run" for c in doc["checks"])
    # --quick: the lobe models and samplers outside its sets are listed, by name, as not run
    run = [c for c in doc["checks"] if c["status"] == "pass"]
    for m in INFO:
        listed = [c for c in doc["checks"] if c["section"] == "models" and c["name"].startswith(m + ":")]
        assert listed and all((c["status"] == "pass") == (m in QUICK_MODELS) for c in listed), m
    for s in STRATEGIES:
        listed = [c for c in doc["checks"] if c["name"].startswith(f"chi-square {s},")]
        # the quick run's strategies at its one point (mu_o = 0.02, r = 1); every other row not run
        assert listed and all(
            (c["status"] == "pass") == (s in QUICK_STRATEGIES and "mu_o = 0.02, r = 1:" in c["name"]) for c in listed
        ), s
    assert len(run) > 40
    ids = [c["id"] for c in doc["checks"]]
    assert len(set(ids)) == len(ids) and all(i.startswith(c["section"] + ".") for i, c in zip(ids, doc["checks"]))
    titles = [s["title"] for s in doc["sections"]]
    assert len(set(titles)) == len(titles)  # section names unique
    assert doc["implementation"] is None
    names = {c["name"] for c in doc["checks"]}
    assert "eon: white furnace |E - 1| at rho = 1" in names
    assert any(n.startswith("chi-square") for n in names)
    assert "Eq. 14 fit of E_F: max fractional error" in names
    assert any(n.startswith("rho_ms_extra_rho") for n in names)
    assert "stated value E_F(mu = 1, r = 1)" in names


def _fake_section(monkeypatch, key, build):
    mod = types.ModuleType(f"openpbr_diffuse.report.sections.{key}")
    mod.TITLE = key
    mod.build = build
    monkeypatch.setitem(sys.modules, mod.__name__, mod)


EVIL = "<script>alert(1)</script>"


def test_strings_from_user_files_are_escaped(tmp_path, monkeypatch):
    """A material named <script>alert(1)</script> (and a path holding it) reach the page escaped."""

    def build(ctx):
        return SectionResult(
            "materials",
            f"Material {EVIL}",
            checks=[Check(f"{EVIL} albedo", 0.5, 1.0, reference=EVIL, detail=EVIL)],
            tables=[Table(EVIL, ["name", EVIL], [[EVIL, 1.0]])],
            notes=[f"material {EVIL} from {ctx.paths[0]}"],
            warnings=[EVIL],
        )

    _fake_section(monkeypatch, "materials", build)
    evil_dir = tmp_path / "<script>alert(1)<" / "script>"
    evil_dir.mkdir(parents=True)
    material = evil_dir / "m.usda"
    material.write_text("#usda 1.0\n")
    out = tmp_path / "out"
    run = runner.run_report([material], out, quick=True, progress=False, sections=["materials"])
    html = (out / "index.html").read_text()
    assert run.passed and EVIL not in html and "<script" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    page = parse(out / "index.html")
    assert page.scripts == 0 and EVIL in "".join(page.text)  # shown as text
    assert json.loads((out / "report.json").read_text())["sections"][0]["notes"][0].count(EVIL) == 2


def test_failed_run_leaves_the_old_report_intact(tmp_path, monkeypatch):
    out = tmp_path / "rep"
    assert runner.run_report(None, out, quick=True, progress=False, sections=["implementations"]).passed
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}

    def broken_render(doc, image_dir=None):
        raise RuntimeError("disk full half-way")

    monkeypatch.setattr("openpbr_diffuse.report.render.render_html", broken_render)
    with pytest.raises(RuntimeError):
        runner.run_report(None, out, quick=True, progress=False, sections=["implementations"])
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert after == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]  # temporary directory removed
    monkeypatch.undo()
    # a complete run replaces it
    assert runner.run_report(None, out, quick=True, progress=False, sections=["implementations"]).passed
    assert (out / "index.html").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]
    # a file the user put into the report folder: the folder is no longer the tool's to replace
    (out / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="did not write"):
        runner.run_report(None, out, quick=True, progress=False, sections=["implementations"])
    assert (out / "notes.txt").read_text() == "mine" and (out / "index.html").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]


def test_failing_and_crashing_sections_exit_1(tmp_path, monkeypatch, capsys):
    def failing(ctx):
        return SectionResult("colorshift", "c", checks=[Check("too big", 2.0, 1.0, reference="test")])

    def crashing(ctx):
        raise ZeroDivisionError("boom")

    _fake_section(monkeypatch, "colorshift", failing)
    _fake_section(monkeypatch, "simulation", crashing)
    run = runner.run_report(None, tmp_path / "r", quick=True, progress=False, sections=["colorshift", "simulation"])
    assert run.exit_status == 1
    doc = run.document
    assert [s["status"] for s in doc["sections"]] == ["fail", "error"]
    assert "boom" in doc["sections"][1]["error"]
    page = parse(tmp_path / "r" / "index.html")
    assert page.sections == {"colorshift": "fail", "simulation": "error"}


def test_missing_section_module_is_not_available(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "openpbr_diffuse.report.sections.approximations", None)
    run = runner.run_report(None, tmp_path / "r", quick=True, progress=False, sections=["approximations"])
    assert run.exit_status == 0 and run.document["sections"][0]["status"] == "not available"


def test_unusable_input_exits_2(tmp_path, capsys):
    assert main(["report", str(tmp_path / "missing.usda"), "--out", str(tmp_path / "r"), "--quick"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing.usda" in err
    assert not (tmp_path / "r").exists()
    (tmp_path / "file").write_text("x")
    assert main(["report", "--out", str(tmp_path / "file"), "--quick"]) == 2
    assert main(["report", str(tmp_path / "file"), "--out", str(tmp_path / "r"), "--quick"]) == 2  # not USD/MaterialX
    assert not (tmp_path / "r").exists()


FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


def test_page_opens_in_chromium_without_errors(quick_report):
    """The page in headless Chromium (Debian's /usr/bin/chromium via playwright): no console
    error, no failed request, every image decoded; a screenshot is saved beside the page."""
    sync_api = pytest.importorskip("playwright.sync_api")
    need("chromium")
    out, _ = quick_report
    url = (out / "index.html").resolve().as_uri()
    console, failed = [], []
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("console", lambda m: console.append((m.type, m.text)))
            page.on("pageerror", lambda e: console.append(("pageerror", str(e))))
            page.on("requestfailed", lambda r: failed.append(r.url))
            page.goto(url, wait_until="load")
            images = page.eval_on_selector_all(
                "img", "els => els.map(e => [e.getAttribute('src'), e.complete, e.naturalWidth])"
            )
            keys = page.eval_on_selector_all("section[data-key]", "els => els.map(e => e.dataset.key)")
            page.screenshot(path=str(out / "screenshot.png"), full_page=True)
        finally:
            browser.close()
    assert [c for c in console if c[0] in ("error", "pageerror")] == []
    assert failed == []
    assert images and all(done and width > 0 for _, done, width in images), images
    assert keys == list(SECTIONS)
    assert (out / "screenshot.png").stat().st_size > 10_000


@pytest.mark.slow
def test_default_report_passes(tmp_path):
    """The default (non-quick) run, as after a fresh install: exit 0, every section shown."""
    out = tmp_path / "report"
    assert main(["report", "--out", str(out), "--no-progress"]) == 0
    page = parse(out / "index.html")
    assert list(page.sections) == list(SECTIONS) and all(s != "fail" for s in page.sections.values())
    # every check --quick lists as not run is one the full report runs, under the same id
    full = {c["id"]: c for c in json.loads((out / "report.json").read_text())["checks"]}
    quick = tmp_path / "quick"
    assert main(["report", "--quick", "--out", str(quick), "--no-progress"]) == 0
    not_run = [c["id"] for c in json.loads((quick / "report.json").read_text())["checks"] if c["status"] == "not run"]
    assert not_run and all(full[i]["status"] == "pass" for i in not_run), [i for i in not_run if i not in full]
