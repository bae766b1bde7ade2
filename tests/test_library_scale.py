"""The report and ``eval --jsonl`` over a material library: streaming, parallel, cached, Dask.

A synthetic library (variants of the bundled materials with other colours and roughnesses,
``openpbr_diffuse.library.synthetic``) is written into a temporary folder, with a USD stage
whose material lives in a sublayer and reads a texture.  Checked against independent
readings: the materials listed equal the readers' own ``load_materials`` of each file, in
the order of the sorted paths; a serial run, a parallel run, a cached run and a Dask run give
the same ``report.json`` materials; editing a sublayer or a texture (or creating a missing
texture) evaluates the material again, to the value written into the file; the page holds one
row per material, a filter that hides rows in Chromium, and a bounded number of pictures.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import subprocess
import sys
import time
from html.parser import HTMLParser
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.library import Cache, LibraryOptions, Task, list_files, process_file, run
from openpbr_diffuse.library.cache import NOT_IN_THE_WORK
from openpbr_diffuse.library.pool import CRASHED
from openpbr_diffuse.library.synthetic import write_variants
from openpbr_diffuse.readers import load_materials
from openpbr_diffuse.readers.evaluate import evaluate
from openpbr_diffuse.report import runner
from openpbr_diffuse.report.junit import junit_xml
from openpbr_diffuse.report.library_html import PAGE

ROOT = Path(__file__).resolve().parents[1]
N_VARIANTS = 40
PREVIEWS = 3
OLD = time.time() - 3600.0  # files written before the run (the cache keeps only those)


def backdate(folder: Path) -> None:
    for p in [*folder.rglob("*"), folder]:
        os.utime(p, (OLD, OLD))


def png(path: Path, rgb: tuple) -> None:
    """A 4x4 PNG of one sRGB colour (8 bit), written with OpenImageIO."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(np.ascontiguousarray(np.broadcast_to(np.asarray(rgb, np.float32), (4, 4, 3))))
    assert buf.write(str(path), "uint8")


LAYER = """#usda 1.0
def Scope "Materials"
{{
    def Material "layered"
    {{
        token outputs:surface.connect = </Materials/layered/Preview.outputs:surface>
        def Shader "Preview"
        {{
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </Materials/layered/Tex.outputs:rgb>
            float inputs:metallic = {metallic}
            token outputs:surface
        }}
        def Shader "Tex"
        {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @{texture}@
            token inputs:sourceColorSpace = "raw"
            float4 inputs:fallback = (0.25, 0.25, 0.25, 1)
            float3 outputs:rgb
        }}
    }}
}}
"""
ROOT_LAYER = """#usda 1.0
(
    subLayers = [@layer.usda@]
)
"""


def write_stage(folder: Path, metallic: float = 0.3, texture: str = "tex.png") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "layer.usda").write_text(LAYER.format(metallic=metallic, texture=texture))
    (folder / "root.usda").write_text(ROOT_LAYER)
    return folder / "root.usda"


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    """A library folder: N_VARIANTS variants, a stage with a sublayer and a texture, a broken file."""
    folder = tmp_path_factory.mktemp("lib") / "library"
    write_variants(folder / "variants", N_VARIANTS, seed=7)
    write_stage(folder / "stage")
    png(folder / "stage" / "tex.png", (0.2, 0.4, 0.6))
    (folder / "broken.mtlx").write_text("<materialx version='1.39'><oops")
    backdate(folder)
    return folder


def expected_materials(folder: Path) -> list[tuple[str, str]]:
    """(relpath, material path) of every material, read with the readers themselves, paths sorted."""
    out = []
    for f in sorted(p for p in folder.rglob("*") if p.suffix in (".mtlx", ".usda") and p.is_file()):
        rel = f.relative_to(folder).as_posix()
        try:
            out += [(rel, m.path) for m in load_materials(f)]
        except ValueError:
            out.append((rel, None))
    return out


def materials_of(out: Path) -> list[dict]:
    return json.loads((out / "report.json").read_text())["materials"]


def report(paths, out, **library):
    return runner.run_report(
        [str(p) for p in paths],
        out,
        quick=True,
        progress=False,
        sections=["materials"],
        library=LibraryOptions(**library),
    )


@pytest.fixture(scope="module")
def serial(library, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "report"
    report([library], out, jobs=1, previews=PREVIEWS)
    return out


def test_every_material_is_listed_in_path_order(library, serial):
    mats = materials_of(serial)
    assert [(m["relpath"], m["material"]) for m in mats] == expected_materials(library)
    assert len(mats) > N_VARIANTS
    bad = [m for m in mats if m["relpath"] == "broken.mtlx"]
    assert len(bad) == 1 and bad[0]["verdict"] == "fail" and bad[0]["reasons"] == ["file not read"]
    # the variants' roughness is what was written into each file
    (clay,) = [m for m in mats if m["relpath"].endswith("00004_clay_rough.mtlx")]
    text = (library / "variants" / "v000" / "00004_clay_rough.mtlx").read_text()
    written = float(re.search(r'base_diffuse_roughness" type="float" value="([^"]+)"', text).group(1))
    assert clay["roughness"] == pytest.approx(written, abs=1e-9)


def test_parallel_and_cached_runs_give_the_serial_materials(library, serial, tmp_path):
    cache = Cache(tmp_path / "cache")
    report([library], tmp_path / "cold", jobs=2, cache=cache, previews=PREVIEWS)
    assert cache.written >= len(list_files([library])) - 1  # every file read but the broken one is kept
    warm = report([library], tmp_path / "warm", jobs=2, cache=Cache(tmp_path / "cache"), previews=PREVIEWS)
    for out in ("cold", "warm"):
        assert materials_of(tmp_path / out) == materials_of(serial), out
    notes = warm.document["sections"][0]["notes"][-1]
    assert notes.startswith("Files: 1 read") and f"{len(list_files([library])) - 1} from the cache" in notes


def test_dask_run_gives_the_serial_materials_and_names_an_unreachable_file(library, serial, tmp_path):
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        report([library], tmp_path / "dask", client=client, previews=PREVIEWS)
        # a file the workers cannot reach (here: it is gone) is reported for that file alone
        clay = str(ROOT / "materials" / "clay_rough.mtlx")
        outcomes = list(run([(clay, Task()), (str(tmp_path / "gone.mtlx"), Task())], client=client))
    assert materials_of(tmp_path / "dask") == materials_of(serial)
    assert outcomes[0].payload["error"] is None and outcomes[0].payload["records"][0]["material"] == "clay_rough"
    assert "gone.mtlx: no such file on Dask worker tcp://" in outcomes[1].payload["error"]


def fresh(stage: Path) -> dict:
    """The diffuse weight and base colour of the stage's material, read and evaluated now."""
    (m,) = load_materials(stage)
    ev = evaluate(m, [30.0], [30.0], [180.0])
    return {"diffuse_weight": ev["diffuse"]["weight"][0], "base_color": list(m.node_inputs["base_color"].value)}


def test_editing_a_sublayer_or_a_texture_evaluates_the_material_again(tmp_path):
    stage = write_stage(tmp_path / "s", metallic=0.3)
    png(tmp_path / "s" / "tex.png", (0.2, 0.4, 0.6))
    other = tmp_path / "s" / "clay.mtlx"
    other.write_text((ROOT / "materials" / "clay_rough.mtlx").read_text())
    backdate(tmp_path / "s")
    cache = Cache(tmp_path / "cache")
    items = [(str(stage), Task()), (str(other), Task())]

    def once():
        outs = list(run(items, cache=cache))
        return [o.cached for o in outs], outs[0].payload["records"][0]

    assert once()[0] == [False, False]
    cached, first = once()
    assert cached == [True, True] and first["diffuse_weight"] == pytest.approx(fresh(stage)["diffuse_weight"])
    # the sublayer: the material evaluated again (less diffuse, more metal), the other file still cached
    write_stage(tmp_path / "s", metallic=0.7)
    cached, rec = once()
    assert cached == [False, True] and rec["diffuse_weight"][0] < first["diffuse_weight"][0]
    assert rec["diffuse_weight"] == pytest.approx(fresh(stage)["diffuse_weight"], abs=1e-12)
    # the texture: the new colour
    png(tmp_path / "s" / "tex.png", (0.6, 0.4, 0.2))
    cached, rec = once()
    assert cached[0] is False and rec["base_color"] != first["base_color"]
    assert rec["base_color"] == pytest.approx(fresh(stage)["base_color"], abs=1e-12)
    assert rec["base_color"][0] > rec["base_color"][2]  # the texel is red-ish now, blue-ish before
    # a texture that was missing (the fallback was used) and appears
    write_stage(tmp_path / "s", metallic=0.7, texture="late.png")
    backdate(tmp_path / "s")
    cached, missing = once()
    cached, again = once()
    assert cached[0] is True and again == missing
    png(tmp_path / "s" / "late.png", (0.9, 0.9, 0.9))
    cached, found = once()
    assert cached[0] is False and found["base_color"] != missing["base_color"]
    assert missing["base_color"] == pytest.approx([0.25, 0.25, 0.25], abs=1e-6)  # the fallback, grey


def test_a_corrupt_cache_entry_is_ignored_and_replaced(tmp_path):
    clay = str(ROOT / "materials" / "clay_rough.mtlx")
    cache = Cache(tmp_path / "cache")
    (good,) = run([(clay, Task())], cache=cache)
    entry = cache.entry_path(clay, Task())
    for garbage in (b"{not json", b'{"path": 3}', b"\xff\xfe", b""):
        entry.write_bytes(garbage)
        (o,) = run([(clay, Task())], cache=Cache(tmp_path / "cache"))
        assert not o.cached and o.payload == good.payload
        assert json.loads(entry.read_text())["payload"] == good.payload  # written anew, whole
    assert sorted(p.name for p in entry.parent.iterdir()) == [entry.name]  # no temporary file left


def test_a_cache_that_cannot_be_written_loses_only_the_cache(tmp_path, capsys):
    (tmp_path / "cache").mkdir()
    (tmp_path / "cache" / "v1").write_text("mine")  # where the entries would go: a file of the user's
    folder = tmp_path / "lib"
    folder.mkdir()
    (folder / "clay.mtlx").write_text((ROOT / "materials" / "clay_rough.mtlx").read_text())
    backdate(folder)
    done = report([folder], tmp_path / "r", jobs=1, cache=Cache(tmp_path / "cache"))
    assert [m["material"] for m in done.document["materials"]] == ["clay_rough"]
    assert any("the cache could not be written" in w for w in done.document["sections"][0]["warnings"])
    assert (tmp_path / "cache" / "v1").read_text() == "mine"
    # --cache-dir naming a file: refused before any work, one line, exit 2
    argv = [
        "report",
        str(folder),
        "--quick",
        "--out",
        str(tmp_path / "r2"),
        "--cache-dir",
        str(tmp_path / "cache" / "v1"),
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is not a folder" in err and not (tmp_path / "r2").exists()


def test_a_file_written_just_now_is_not_kept(tmp_path):
    f = tmp_path / "clay.mtlx"
    f.write_text((ROOT / "materials" / "clay_rough.mtlx").read_text())
    assert process_file(str(f), Task())["cacheable"] is False  # it may still be being written
    os.utime(f, (OLD, OLD))
    assert process_file(str(f), Task())["cacheable"] is True


def crash_on_bad(path, task):
    """Work that kills its worker process on a file named *bad* (as a crash in a native
    library would), and names the others."""
    if "bad" in os.path.basename(path):
        os._exit(3)
    return {"path": path, "payload": {"records": [{"material": os.path.basename(path)}], "error": None}}


def test_a_crashing_worker_loses_only_its_file(tmp_path):
    src = ROOT / "materials" / "clay_rough.mtlx"
    files = []
    for i in range(10):
        f = tmp_path / (f"{i:02d}_bad.mtlx" if i == 4 else f"{i:02d}.mtlx")
        f.write_text(src.read_text())
        files.append(str(f))
    outs = list(run([(f, Task()) for f in files], jobs=2, work=crash_on_bad))
    assert [o.index for o in outs] == list(range(10))
    assert [o.payload["error"] is None for o in outs] == [i != 4 for i in range(10)]
    assert outs[4].payload["error"].endswith(CRASHED)
    assert [o.payload["records"][0]["material"] for o in outs if o.index != 4] == [
        os.path.basename(f) for k, f in enumerate(files) if k != 4
    ]


def test_progress_lines_when_stderr_is_not_a_terminal(library, tmp_path, capsys):
    sub = library / "stage"
    assert (
        main(["report", str(sub), "--quick", "--select", "materials", "--out", str(tmp_path / "r"), "--no-cache"]) == 0
    )
    err = capsys.readouterr().err
    assert "report: section 1/1 materials" in err
    # two files: root.usda and the sublayer it composes (a material file of its own)
    assert re.search(r"^materials: 0/2 files$", err, re.M) and re.search(r"^materials: 2/2 files in \d+ s$", err, re.M)
    assert "\r" not in err  # lines, not a bar
    code = main(["eval", str(sub), "--jsonl", str(tmp_path / "m.jsonl"), "--no-cache"])
    assert code == 0 and re.search(r"^eval: 2/2 files in \d+ s$", capsys.readouterr().err, re.M)
    assert (
        main(["report", str(sub), "--quick", "--select", "materials", "--out", str(tmp_path / "q"), "--no-progress"])
        == 0
    )
    assert "files" not in capsys.readouterr().err


class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.rows, self.inputs, self.scripts, self.csp, self.in_script = [], [], [], "", False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "tr" and "data-verdict" in a:
            self.rows.append(a["data-verdict"])
        elif tag == "input":
            self.inputs.append(a.get("id"))
        elif tag == "script":
            self.scripts.append("")
            self.in_script = True
        elif tag == "meta" and a.get("http-equiv") == "Content-Security-Policy":
            self.csp = a["content"]

    def handle_endtag(self, tag):
        if tag == "script":
            self.in_script = False

    def handle_data(self, data):
        if self.in_script:
            self.scripts[-1] += data


def test_the_page_has_a_row_per_material_a_filter_and_one_allowed_script(serial):
    page = _Page()
    page.feed((serial / "index.html").read_text(encoding="utf-8"))
    mats = materials_of(serial)
    assert len(page.rows) == len(mats) and sorted(page.rows) == sorted(m["verdict"] for m in mats)
    assert page.rows[0] == "fail"  # the worst first
    assert "materials-filter" in page.inputs
    (script,) = page.scripts
    digest = "'sha256-" + __import__("base64").b64encode(hashlib.sha256(script.encode()).digest()).decode() + "'"
    assert f"script-src {digest}" in page.csp and "default-src 'none'" in page.csp


def test_paths_from_files_reach_the_table_escaped(tmp_path):
    folder = tmp_path / "<b>lib"
    (folder / "<script>").mkdir(parents=True)
    (folder / "<script>" / "<i>clay.mtlx").write_text((ROOT / "materials" / "clay_rough.mtlx").read_text())
    out = tmp_path / "r"
    report([folder], out, jobs=1)
    html = (out / "index.html").read_text()
    assert "<i>clay" not in html and "<td>&lt;script&gt;/&lt;i&gt;clay.mtlx</td>" in html  # relative to the folder
    assert html.count("<script") == 1  # the page's own


def test_pictures_are_bounded_by_the_cap(serial, library):
    images = sorted(p.name for p in (serial / "images").iterdir())
    assert len(materials_of(serial)) > 10 * PREVIEWS
    assert images.count("materials_distributions.png") == 1
    assert sum(n.endswith("_render.png") for n in images) == PREVIEWS
    assert sum(n.endswith("_albedo.png") for n in images) == PREVIEWS
    assert len(images) == 1 + 2 * PREVIEWS


def test_junit_has_a_case_per_material(serial):
    doc = json.loads((serial / "report.json").read_text())
    root = ET.fromstring(junit_xml(doc))
    (suite,) = [s for s in root if s.get("name") == "materials.library"]
    assert int(suite.get("tests")) == len(doc["materials"])
    assert int(suite.get("failures")) == sum(m["verdict"] == "fail" for m in doc["materials"])
    assert any(s.get("name") == "materials" for s in root)  # the section's checks keep their cases


def test_eval_jsonl_lines_are_eval_json_entries(tmp_path, capsys):
    files = [ROOT / "materials" / n for n in ("clay_rough.mtlx", "paint_variants.usda", "sand_oren_nayar.mtlx")]
    out = tmp_path / "m.jsonl"
    argv = ["--theta-i", "0", "45", "--theta-o", "30", "--variant", "finish=gloss"]
    assert main(["eval", *map(str, files), "--jsonl", str(out), "--jobs", "1", "--no-cache", *argv]) == 1
    capsys.readouterr()
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    expected = []
    for f in files:
        code = main(["eval", str(f), "--json", *argv])
        printed = capsys.readouterr()
        expected += json.loads(printed.out)["materials"] if code in (0, 1) else [printed.err]
    assert len(lines) == len(expected)
    for line, exp in zip(lines, expected):
        if isinstance(exp, str):  # variants apply to USD only: the MaterialX files cannot be read so
            assert line["path"] is None and exp == f"openpbr-diffuse eval: error: {line['error']}\n"
        else:
            assert {k: v for k, v in line.items() if k not in ("relpath", "index")} == exp
    # OUT follows the output-file rule: not replaced without --force, then replaced whole
    assert main(["eval", str(files[0]), "--jsonl", str(out), "--no-cache"]) == 2
    assert "exists" in capsys.readouterr().err and len(out.read_text().splitlines()) == len(lines)
    assert main(["eval", str(files[0]), "--jsonl", str(out), "--no-cache", "--force"]) == 0
    assert len(out.read_text().splitlines()) == 1 and sorted(p.name for p in tmp_path.iterdir()) == ["m.jsonl"]


def test_the_code_fingerprint_leaves_out_only_what_the_work_never_imports():
    code = (
        "import sys\n"
        "from openpbr_diffuse.library import Task, list_files, process_file\n"
        "from openpbr_diffuse.readers import BUNDLED_MATERIALS\n"
        "for f in list_files([BUNDLED_MATERIALS]):\n"
        "    for t in (Task(), Task(kind='eval'), Task(kind='detail', select=(0, 1))):\n"
        "        process_file(f.path, t)\n"
        "print('\\n'.join(m for m in sys.modules if m.startswith('openpbr_diffuse.')))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    used = {m.split(".")[1] for m in proc.stdout.split()}
    assert "readers" in used and "nodes" in used
    assert not used & {n.removesuffix(".py") for n in NOT_IN_THE_WORK}


def test_chromium_filter_hides_rows(serial):
    """Type into the filter in headless Chromium: only the matching rows stay visible."""
    from _browser import opened_page

    mats = materials_of(serial)
    want = sum("clay_rough" in m["relpath"] for m in mats)
    with opened_page(serial / "index.html", {"width": 1280, "height": 900}) as (page, errors):
        visible = "() => [...document.querySelectorAll('#materials-table tbody tr')].filter(r => !r.hidden).length"
        before = page.evaluate(visible)
        page.fill("#materials-filter", "clay_rough")
        after = page.evaluate(visible)
        shown = page.inner_text("#materials-shown")
        page.select_option("#materials-verdict", "fail")
        failing = page.evaluate(visible)
        wide = page.evaluate("() => document.documentElement.scrollWidth <= window.innerWidth")
    assert errors == []
    assert before == len(mats) and 0 < want == after < before
    assert shown == f"{want} of {len(mats)} materials shown"
    assert failing == 0  # no clay variant fails
    assert wide  # no sideways scroll


@pytest.mark.corpus
@pytest.mark.slow
def test_realworld_corpus_in_parallel(tmp_path):
    corpus = ROOT.parent / "shared" / "corpus" / "realworld"
    if not corpus.is_dir():
        pytest.skip("../shared/corpus/realworld is absent")
    run_ = report([corpus], tmp_path / "r", jobs=2, previews=24)
    mats = run_.document["materials"]
    # every material the readers list, one record for each file they cannot read, in path order
    expected = []
    for f in list_files([corpus]):
        try:
            expected += [(f.path, m.path) for m in load_materials(f.path)]
        except (ValueError, TypeError, OSError):
            expected.append((f.path, None))
    assert [(m["file"], m["material"]) for m in mats] == expected
    assert len(list((tmp_path / "r" / "images").iterdir())) <= 1 + 2 * 24


@pytest.mark.slow
def test_ten_thousand_files_open_in_chromium_within_3_s_and_filter(tmp_path):
    """10^4 synthetic material files (variants of the bundled library, written by the tool):
    the materials section reports every one, and the page opens in headless Chromium within
    3 s (navigation to the load event) with its filter working on all rows."""
    from _system import need
    from playwright import sync_api
    from test_report_page import CHROMIUM, FLAGS

    need("chromium")
    n = 10_000
    write_variants(tmp_path / "lib", n, seed=7)
    out = tmp_path / "report"
    report([tmp_path / "lib"], out, jobs=2)
    mats = materials_of(out)
    assert len({m["relpath"] for m in mats}) == n
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            t0 = time.perf_counter()
            page.goto((out / "index.html").resolve().as_uri(), wait_until="load")
            opened = time.perf_counter() - t0
            rows = "() => [...document.querySelectorAll('#materials-table tbody tr')]"
            total = page.evaluate(f"() => ({rows})().length")
            t0 = time.perf_counter()
            page.fill("#materials-filter", "clay_rough")
            visible = page.evaluate(f"() => ({rows})().filter(r => !r.hidden).length")
            filtered = time.perf_counter() - t0
            shown = page.inner_text("#materials-shown")
            page.click("#materials-more")
            every = page.evaluate(f"() => ({rows})().filter(r => !r.hidden).length")
        finally:
            browser.close()
    want = sum("clay_rough" in m["relpath"] for m in mats)
    # at most the first PAGE matching rows are laid out; the count says how many match
    assert total == len(mats) and 0 < visible == min(want, PAGE) < total
    assert shown.startswith(f"{want} of {len(mats)} materials shown")
    assert every == want  # "show all" lists every match
    assert opened < 3.0, f"the page took {opened:.1f} s to open"
    assert filtered < 3.0, f"filtering took {filtered:.1f} s"
