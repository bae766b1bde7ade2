"""`template glsl|cpp|csv` writes starting files that run as they are and are never written
over without --force; blank rows are skipped; JSON rows take `out` without a columns list."""

import json
import subprocess

import numpy as np
import pytest
from _system import requires

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.deviations import reference
from openpbr_diffuse.conformance.vectors import (
    COLUMNS,
    OUT_COLUMNS,
    default_vectors,
    read_results,
)

V = default_vectors()


@pytest.mark.parametrize("kind", ["glsl", "cpp", "csv"])
def test_template_is_never_written_over(tmp_path, capsys, kind):
    path = tmp_path / f"t.{kind}"
    path.write_text("mine\n")
    assert main(["template", kind, "--out", str(path)]) == 2
    assert path.read_text() == "mine\n"
    assert "--force" in capsys.readouterr().err
    assert main(["template", kind, "--out", str(path), "--force"]) == 0
    assert path.read_text() != "mine\n"


@pytest.mark.parametrize(
    "kind,sig",
    [
        (
            "glsl",
            [
                "vec3 f(vec3 wi, vec3 wo, float roughness, vec3 rho)",
                "vec3 albedo(float mu, float roughness, vec3 rho)",
                "vec3 sample_wi(vec3 wo, vec2 u, float roughness)",
                "float pdf(vec3 wo, vec3 wi, float roughness)",
            ],
        ),
        (
            "cpp",
            [
                "glm::vec3 f(glm::vec3 wi, glm::vec3 wo, float roughness, glm::vec3 rho)",
                "glm::vec3 albedo(float mu, float roughness, glm::vec3 rho)",
                "glm::vec3 sample_wi(glm::vec3 wo, glm::vec2 u, float roughness)",
                "float pdf(glm::vec3 wo, glm::vec3 wi, float roughness)",
            ],
        ),
    ],
)
def test_template_signatures_and_placeholder(tmp_path, kind, sig):
    path = tmp_path / f"t.{kind}"
    assert main(["template", kind, "--out", str(path)]) == 0
    text = path.read_text()
    assert all(s in text for s in sig) and "PLACEHOLDER" in text


@requires("glm")
def test_cpp_template_compiles_and_is_lambert(tmp_path):
    """Compiled with a main of its own: f = rho/pi, E = rho, the sample's pdf is mu/pi."""
    path = tmp_path / "t.cpp"
    assert main(["template", "cpp", "--out", str(path)]) == 0
    (tmp_path / "main.cpp").write_text(
        f'#include "{path}"\n#include <cstdio>\nint main() {{\n'
        '  glm::vec3 wi = sample_wi(glm::vec3(0, 0, 1), glm::vec2(0.3f, 0.7f), 0.5f);\n'
        '  glm::vec3 v = f(wi, glm::vec3(0.6f, 0, 0.8f), 0.5f, glm::vec3(0.5f));\n'
        '  glm::vec3 e = albedo(0.4f, 0.5f, glm::vec3(0.25f));\n'
        '  std::printf("%.7g %.7g %.7g %.7g\\n", v.x, e.x, pdf(glm::vec3(0, 0, 1), wi, 0.5f), wi.z);\n}\n'
    )
    exe = tmp_path / "a.out"
    subprocess.run(["g++", "-std=c++17", "-O1", str(tmp_path / "main.cpp"), "-o", str(exe)], check=True, timeout=120)
    v, e, p, z = map(float, subprocess.run([str(exe)], capture_output=True, text=True, timeout=30).stdout.split())
    assert v == pytest.approx(0.5 / np.pi, rel=1e-6) and e == pytest.approx(0.25)
    assert p == pytest.approx(z / np.pi, rel=1e-6) and z == pytest.approx(np.sqrt(0.7), rel=1e-6)


def test_csv_template_filled_in_part_is_graded(tmp_path, capsys):
    path = tmp_path / "v.csv"
    assert main(["template", "csv", "--out", str(path)]) == 0
    lines = path.read_text().splitlines()
    head = [ln for ln in lines if not ln.startswith("#")][0].split(",")
    assert head == list(COLUMNS + OUT_COLUMNS)
    ref = reference(V)
    eon = set(np.flatnonzero(V.model == "eon").tolist())
    k, new = 0, []
    for ln in lines:
        if ln.startswith("#") or ln.startswith("id,"):
            new.append(ln)
            continue
        if k in eon:  # only the EON rows filled in
            ln = ln[:-3] + "," + ",".join(f"{x:.9g}" for x in ref[k])
        new.append(ln)
        k += 1
    path.write_text("\n".join(new) + "\n")
    capsys.readouterr()
    assert main(["check", str(path), "--json"]) == 0  # without --model
    d = json.loads(capsys.readouterr().out)
    assert d["n_rows"] == len(eon) and d["n_skipped"] == len(V) - len(eon) and d["models"] == ["eon"]
    vec, out, skipped = read_results(path, with_skipped=True)
    assert len(vec) == len(eon) and skipped == len(V) - len(eon)


def test_json_rows_take_out_without_a_columns_list(tmp_path, capsys):
    path = tmp_path / "v.json"
    assert main(["vectors", "--out", str(path)]) == 0
    doc = json.loads(path.read_text())
    doc["columns"] = list(COLUMNS)  # the out columns not listed
    ref = reference(V)
    for i, row in enumerate(doc["rows"]):
        for c in OUT_COLUMNS:
            row.pop(c, None)
        if i % 2:
            row["out"] = [float(x) for x in ref[i]]
        elif i % 4 == 0:
            row.update({c: float(x) for c, x in zip(OUT_COLUMNS, ref[i])})
    path.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["check", str(path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["n_skipped"] == sum(1 for i in range(len(V)) if i % 2 == 0 and i % 4 != 0)
    assert d["n_rows"] + d["n_skipped"] == len(V)
