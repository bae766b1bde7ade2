"""The WGSL child process of the Babylon.js grader: without wgpu (a test dependency) the grader
reports the missing package in one line instead of a silent or hidden failure."""

import numpy as np
import pytest

from openpbr_diffuse.graders import babylon
from openpbr_diffuse.graders.errors import GraderUnavailable


def test_missing_wgpu_is_named(tmp_path, monkeypatch):
    (tmp_path / "wgpu.py").write_text("raise ModuleNotFoundError(\"No module named 'wgpu'\", name='wgpu')\n")
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    with pytest.raises(GraderUnavailable, match=r"label \(WGSL\): ModuleNotFoundError: No module named 'wgpu'"):
        babylon._run_wgsl("@compute @workgroup_size(64) fn main() {}", np.zeros((2, 10)), 3, "label")


def test_missing_wgpu_is_named_when_a_child_already_runs(tmp_path, monkeypatch):
    """The WGSL child serves a process's runs one after the other; a changed environment (here
    one that hides wgpu) starts a new one, as a child per run would see it."""
    from openpbr_diffuse.graders import limits

    try:  # a child with the real wgpu (it may have no adapter here: only the environment matters)
        babylon._run_wgsl("@compute @workgroup_size(64) fn main() {}", np.zeros((2, 10)), 3, "label")
    except GraderUnavailable:
        pass
    test_missing_wgpu_is_named(tmp_path, monkeypatch)
    limits.stop_workers()
