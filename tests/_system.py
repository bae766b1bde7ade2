"""System programs the tests use, in one place: what each is, how to install it, and one skip.

On a user's machine a test that needs a missing system program (Chromium, g++ and GLM, Mesa's
EGL/llvmpipe, Mesa's Vulkan driver, node and npm) is skipped with one line that names what to
install.  ``.ci/run`` installs all of them and sets ``OPENPBR_DIFFUSE_REQUIRE_SYSTEM=1``: under
it such a skip is a failure (``conftest.py`` turns every skip whose reason starts with
:data:`PREFIX` into one), so nothing is skipped there for lack of a program.

    from _system import requires, need
    @requires("gl")
    def test_runs_glsl(): ...
    def test_page():
        need("chromium")
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

#: every system-program skip reason starts with this (conftest.py recognises it)
PREFIX = "needs a system program:"
#: set by .ci/run: a system-program skip is a failure
REQUIRE_ENV = "OPENPBR_DIFFUSE_REQUIRE_SYSTEM"

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


@functools.cache
def _child_ok(code: str) -> bool:
    """``code`` runs in a child Python without error (a missing driver cannot crash the tests)."""
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


@functools.cache
def _glm_ok() -> bool:
    return any(Path(d, "glm", "glm.hpp").is_file() for d in ("/usr/include", "/usr/local/include"))


@functools.cache
def _grader_ok(module: str, function: str) -> bool:
    """``openpbr_diffuse.MODULE.FUNCTION()`` finds what it reads (an npm package, bpy): it
    raises GraderUnavailable, naming the install command, when that is missing."""
    import importlib

    from openpbr_diffuse.graders.errors import GraderUnavailable

    try:
        getattr(importlib.import_module(f"openpbr_diffuse.{module}"), function)()
    except GraderUnavailable:
        return False
    return True


#: name -> (what it is, how to install it, availability test)
PROGRAMS = {
    "chromium": ("Chromium", "apt-get install chromium", lambda: Path(CHROMIUM).exists()),
    "g++": ("g++", "apt-get install g++", lambda: shutil.which("g++") is not None),
    "gcc": ("gcc", "apt-get install gcc", lambda: shutil.which("gcc") is not None),
    "glm": ("g++ and GLM", "apt-get install g++ libglm-dev", lambda: shutil.which("g++") is not None and _glm_ok()),
    "gl": (
        "OpenGL 4.3 through EGL (Mesa llvmpipe)",
        "apt-get install libgl1-mesa-dri libegl1 libegl-mesa0",
        lambda: _child_ok("from openpbr_diffuse.graders.glsl import gl_context; gl_context()"),
    ),
    "vulkan": (
        "a Vulkan driver for wgpu (Mesa lavapipe)",
        "apt-get install mesa-vulkan-drivers",
        # wgpu finds an adapter (Mesa's lavapipe without a GPU)
        lambda: _child_ok("import wgpu; wgpu.gpu.request_adapter_sync(power_preference='high-performance')"),
    ),
    "babylonjs": (
        "Babylon.js (npm @babylonjs/core)",
        "npm install --prefix ~/.cache/openpbr-diffuse/npm @babylonjs/core",
        lambda: _grader_ok("graders.babylon", "package_folder"),
    ),
    "babylonjs-loaders": (
        "Babylon.js's glTF loader (npm @babylonjs/loaders)",
        "npm install --prefix ~/.cache/openpbr-diffuse/npm --ignore-scripts @babylonjs/core @babylonjs/loaders",
        lambda: _grader_ok("renderers.babylonjs", "version"),
    ),
    "threejs": (
        "three.js (npm three)",
        "npm install --prefix ~/.cache/openpbr-diffuse/npm --ignore-scripts three",
        lambda: _grader_ok("graders.threejs", "package_folder"),
    ),
    "three-gpu-pathtracer": (
        "three-gpu-pathtracer (npm)",
        "npm install --prefix ~/.cache/openpbr-diffuse/npm --ignore-scripts three three-gpu-pathtracer",
        lambda: _grader_ok("graders.threejs_pathtracer", "package_folder"),
    ),
    "bpy": (
        "Blender's bpy in a Python of its own",
        "python3.11 -m venv bpy-env && bpy-env/bin/pip install bpy; export OPENPBR_DIFFUSE_BPY_PYTHON=$PWD/bpy-env/bin/python",
        lambda: _grader_ok("graders.cycles", "bpy_version"),
    ),
    "xvfb": (
        "Xvfb (MaterialX's GlslRenderer makes its GL context through GLX)",
        "apt-get install xvfb",
        lambda: shutil.which("Xvfb") is not None,
    ),
    "node": ("node and npm", "apt-get install nodejs npm", lambda: bool(shutil.which("node") and shutil.which("npm"))),
}


def available(name: str) -> bool:
    """Whether the system program ``name`` (a key of :data:`PROGRAMS`) is usable here."""
    return bool(PROGRAMS[name][2]())


def reason(name: str) -> str:
    """The one-line skip reason for a missing ``name``."""
    what, install, _ = PROGRAMS[name]
    return f"{PREFIX} {what} is not installed ({install})"


def requires(*names: str) -> pytest.MarkDecorator:
    """A skipif marker: skip (one line naming what to install) unless every program is usable.

    Availability is asked once per program and session (a child process for GL and Vulkan)."""
    missing = [n for n in names if not available(n)]
    return pytest.mark.skipif(bool(missing), reason="; ".join(reason(n) for n in missing) or "available")


def need(*names: str) -> None:
    """Inside a test or fixture: skip (or fail under :data:`REQUIRE_ENV`) unless every program is usable."""
    for n in names:
        if not available(n):
            pytest.skip(reason(n))


def required() -> bool:
    """Whether a missing system program fails the run (``.ci/run``) instead of skipping."""
    return os.environ.get(REQUIRE_ENV, "") not in ("", "0")
