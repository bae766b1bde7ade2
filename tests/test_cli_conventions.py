"""Command-line conventions: one-line errors naming the program once,
negative numbers as values, no silently ignored options, quiet broken pipes and Ctrl-C."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from openpbr_diffuse.cli.main import main

ROOT = Path(__file__).resolve().parents[1]


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def cli(*argv, **kw):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", *argv], capture_output=True, text=True, env=env, **kw
    )


def test_program_name_appears_once(capsys):
    code, out, err = run(capsys, "albedo")
    assert code == 2 and err.count("openpbr-diffuse") == 1 and err.startswith("openpbr-diffuse albedo: error:")
    code, out, err = run(capsys, "albedo", "eon", "--roughness", "2", "--mu", "0.5")
    assert code == 2 and err.count("openpbr-diffuse") == 1 and "roughness" in err


@pytest.mark.parametrize("value", ["-inf", "-1e-300", "-.5", "-1E+3", "-nan"])
def test_negative_numbers_are_values(capsys, value):
    code, out, err = run(capsys, "albedo", "eon", "--roughness", value, "--mu", "0.5")
    assert code == 2 and "roughness must" in err and "expected one argument" not in err


@pytest.mark.parametrize(
    "extra",
    [
        ["--roughness", "1"],
        ["--mu", "0.5"],
        ["--average"],
        ["--reference"],
        ["--rho", "0.5"],
        ["--color-mode", "white_tint"],
    ],
)
def test_export_refuses_query_options(capsys, tmp_path, extra):
    code, out, err = run(capsys, "albedo", "eon", "--export", str(tmp_path), *extra)
    assert code == 2 and extra[0] in err and not list(tmp_path.iterdir())


@pytest.mark.parametrize("model", ["qon", "fon", "full_on", "lambert", "qon_fujii"])
def test_white_tint_is_for_eon_models_only(capsys, model):
    rough = [] if model == "lambert" else ["--roughness", "0.5"]
    code, _, err = run(capsys, "albedo", model, *rough, "--mu", "0.5", "--color-mode", "white_tint")
    assert code == 2 and "EON" in err
    code, out, _ = run(
        capsys,
        "albedo",
        "eon_approx",
        "--roughness",
        "0.5",
        "--mu",
        "0.5",
        "--rho",
        "0.5",
        "--color-mode",
        "white_tint",
        "--json",
    )
    assert code == 0 and json.loads(out)["color_mode"] == "white_tint"


def test_lambert_has_no_roughness(capsys):
    code, _, err = run(capsys, "albedo", "lambert", "--roughness", "5", "--mu", "0.5")
    assert code == 2 and "lambert" in err
    code, out, _ = run(capsys, "albedo", "lambert", "--mu", "0.5")
    assert code == 0 and "r = " not in out


def test_export_path_that_is_a_file(capsys, tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    code, _, err = run(capsys, "albedo", "eon", "--export", str(f))
    assert code == 2 and "[Errno" not in err and "not a directory" in err and str(f) in err


def test_help_is_a_description_not_a_docstring():
    proc = cli("--help")
    assert proc.returncode == 0
    assert "``" not in proc.stdout and "entry point" not in proc.stdout and "EON" in proc.stdout


def test_python_dash_m_runs():
    proc = cli("albedo", "lambert", "--mu", "0.5", "--json")
    assert proc.returncode == 0 and json.loads(proc.stdout)["albedo"] == [[1.0]]


def test_broken_pipe_exits_141_quietly():
    mus = [str(i / 20000) for i in range(20001)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen(
        [sys.executable, "-m", "openpbr_diffuse", "albedo", "eon", "--roughness", "1", "--mu", *mus],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    p.stdout.readline()
    p.stdout.close()  # what `| head -1` does
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 141
    assert err == ""


def test_ctrl_c_is_one_line_exit_130(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "openpbr_diffuse",
            "albedo",
            "full_on",
            "--export",
            str(tmp_path),
            "--size",
            "4096",
            "--no-progress",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    # the texture's temporary sibling appears when writing starts: inside the command
    deadline = time.monotonic() + 120
    while not list(tmp_path.glob(".full_on_albedo.exr.*")) and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert p.poll() is None, "the export ended before it could be interrupted"
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert err.decode().strip() == "openpbr-diffuse: interrupted"
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == [], left  # no half-written texture, no temporary file
