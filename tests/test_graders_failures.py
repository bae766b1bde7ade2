"""Clear failures: a missing piece is one line on stderr naming it and how to get it, exit 2."""

from _system import need

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.graders import glsl
from openpbr_diffuse.graders.errors import GraderUnavailable


def run(capsys, *args):
    status = main(["check", *args])
    captured = capsys.readouterr()
    return status, captured.err.strip().splitlines()


def test_source_without_the_expected_files(capsys, tmp_path):
    status, err = run(capsys, "--implementation", "materialx-glsl", "--source", str(tmp_path))
    assert status == 2 and len(err) == 1 and str(tmp_path) in err[0] and "mx_oren_nayar_diffuse_bsdf" in err[0]


def test_no_compiler(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("CXX", "no-such-compiler-here")
    src = tmp_path / "f.hpp"
    src.write_text("glm::vec3 f(glm::vec3 a, glm::vec3 b, float r, glm::vec3 c) { return c; }\n")
    status, err = run(capsys, "--cpp", str(src), "--function", "f")
    assert status == 2 and len(err) == 1 and "apt-get install g++" in err[0]


def test_cpp_compile_error_names_the_line(capsys, tmp_path):
    need("glm")
    src = tmp_path / "broken.hpp"
    src.write_text("glm::vec3 f(glm::vec3 a, glm::vec3 b, float r, glm::vec3 c) { return undefined_name; }\n")
    status, err = run(capsys, "--cpp", str(src), "--function", "f")
    assert status == 2 and len(err) == 1 and "does not compile" in err[0] and "broken.hpp" in err[0]


def test_no_egl(capsys, monkeypatch, tmp_path):
    """No EGL in the GL child (a moderngl whose context fails, first on its import path):
    one line naming what to install, exit 2."""
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "moderngl.py").write_text(
        "def create_standalone_context(**kwargs):\n    raise Exception('libEGL.so.1: cannot open shared object file')\n"
    )
    monkeypatch.setenv("PYTHONPATH", str(fake))
    monkeypatch.setattr(glsl, "_VERSION", None)
    src = tmp_path / "f.glsl"
    src.write_text("vec3 f(vec3 wi, vec3 wo, float r, vec3 rho) { return rho; }\n")
    status, err = run(capsys, "--glsl", str(src), "--function", "f")
    assert status == 2 and len(err) == 1 and "libgl1-mesa-dri" in err[0] and "libEGL" in err[0]


def test_shader_compile_error(capsys, tmp_path):
    try:
        glsl.gl_context()
    except GraderUnavailable:
        need("gl")
    src = tmp_path / "broken.glsl"
    src.write_text("vec3 f(vec3 wi, vec3 wo, float r, vec3 rho) { return rho * undefined_name; }\n")
    status, err = run(capsys, "--glsl", str(src), "--function", "f")
    assert status == 2 and len(err) == 1 and "does not compile" in err[0] and "undefined_name" in err[0]


def test_bpy_missing(capsys, monkeypatch, tmp_path):
    fake = tmp_path / "python"
    fake.write_text("#!/bin/sh\necho \"ModuleNotFoundError: No module named 'bpy'\" >&2\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setenv("OPENPBR_DIFFUSE_BPY_PYTHON", str(fake))
    status, err = run(capsys, "--implementation", "cycles")
    assert status == 2 and len(err) == 1 and "pip install bpy" in err[0]


def test_grader_options_conflict(capsys, tmp_path):
    status, err = run(capsys, "--implementation", "materialx-glsl", "--glsl", str(tmp_path / "x.glsl"))
    assert status == 2 and len(err) == 1
    status, err = run(capsys, "--source", str(tmp_path))
    assert status == 2 and "--implementation" in err[0]
