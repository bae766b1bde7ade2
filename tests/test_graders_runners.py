"""The runners themselves: include resolution, llvmpipe's acos error behind the GLSL tolerance,
and the C++ harness cache."""

import numpy as np
import pytest
from _system import requires

from openpbr_diffuse.graders import cpp, glsl
from openpbr_diffuse.graders.errors import GraderUnavailable


def test_includes_resolve_next_to_the_file_then_on_the_search_path(tmp_path):
    (tmp_path / "lib").mkdir()
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "main.glsl").write_text(
        '#include "near.glsl"\n#include "far.glsl"\n#include "near.glsl"\nmain\n'
    )
    (tmp_path / "sub" / "near.glsl").write_text("near\n")
    (tmp_path / "lib" / "far.glsl").write_text('#include "near2.glsl"\nfar\n')
    (tmp_path / "lib" / "near2.glsl").write_text("near2\n")
    text = glsl.resolve_includes(tmp_path / "sub" / "main.glsl", (tmp_path / "lib",))
    assert text.split() == ["near", "near2", "far", "main"]  # each file once, in order
    with pytest.raises(GraderUnavailable, match="missing.glsl"):
        (tmp_path / "bad.glsl").write_text('#include "missing.glsl"\n')
        glsl.resolve_includes(tmp_path / "bad.glsl")


@requires("gl")
def test_llvmpipe_acos_error_is_within_the_stated_bound():
    """The GLSL tolerance assumes |acos_gl - acos| <= 1.6e-4 (ecosystem.md); measure it."""
    x = np.linspace(-1.0, 1.0, 200_001).astype(np.float32)
    k = glsl.Kernel(code="", body="    OUT(0) = acos(IN(0));", n_in=1, n_out=1)
    err = np.abs(k.run(x[:, None])[:, 0] - np.arccos(x.astype(np.float64)))
    assert 1e-6 < err.max() <= 1.7e-4  # an approximation, and no worse than stated
    # the same through the fragment stage
    k = glsl.Kernel(code="", body="    OUT(0) = acos(IN(0));", n_in=1, n_out=1, stage="fragment")
    assert np.array_equal(
        k.run(x[:1000, None])[:, 0],
        glsl.Kernel(code="", body="    OUT(0) = acos(IN(0));", n_in=1, n_out=1).run(x[:1000, None])[:, 0],
    )


@requires("glm")
def test_cpp_harness_is_cached_by_source_hash(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENPBR_DIFFUSE_CACHE", str(tmp_path / "cache"))
    src = tmp_path / "f.hpp"
    src.write_text("inline float twice(float x) { return VALUE * x; }\n")
    h = cpp.Harness(
        prelude=f'#include "{src}"\n',
        entries={"f": cpp.Entry(1, 1, "out[0] = twice(in[0]);")},
        defines={"VALUE": "2.0f"},
        sources=[src],
    )
    exe = h.binary()
    mtime = exe.stat().st_mtime_ns
    assert h.binary() == exe and exe.stat().st_mtime_ns == mtime  # reused, not rebuilt
    assert h.run("f", np.array([[1.5], [3.0]]))[:, 0].tolist() == [3.0, 6.0]
    src.write_text("inline float twice(float x) { return VALUE * x + 1.0f; }\n")
    assert h.binary() != exe  # new source, new build
    assert h.run("f", np.array([[1.5]]))[:, 0].tolist() == [4.0]
