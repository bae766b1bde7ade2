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
