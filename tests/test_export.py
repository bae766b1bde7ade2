"""``openpbr-diffuse export``: every language rendered from one source, each export graded.

The references are independent of the exported text: ``openpbr-diffuse check`` (the
conformance vectors and the sampler grades), and the library's numba kernels
(``evaluate``, ``directional_albedo``, ``average_albedo``, ``pdf``) for the variants and
the edge inputs the vectors do not hold.
"""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _system import available, requires

import openpbr_diffuse as od
from openpbr_diffuse.export import LANGS, export_files, export_text, grade_command, write_export
from openpbr_diffuse.export.render import neutral_source

ALL = [(lang, "float") for lang in LANGS] + [("cpp", "double")]
#: the stated precision of each export (relative, absolute) against the float64 library
BOUND = {"float": (2e-5, 1e-6), "double": (1e-12, 1e-14)}


def _full(lang, precision):
    """Every file of the export, joined (mtlx: the document and its GLSL implementation)."""
    return "\n".join(text for _, text in export_files(lang, "eon.x", precision))


def _cli(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", *args], capture_output=True, text=True, cwd=cwd, timeout=120
    )


def _grade_argv(path, lang):
    line = [ln for ln in path.read_text().splitlines() if ln.startswith("// grade: ")]
    assert len(line) == 1
    argv = line[0][len("// grade: ") :].replace("FILE", str(path)).split()
    assert argv[:2] == ["openpbr-diffuse", "check"]
    return [sys.executable, "-m", "openpbr_diffuse", *argv[1:]]


@pytest.mark.parametrize("lang,precision", ALL)
def test_header_states_conventions_citation_licence_version_and_one_grade_line(lang, precision):
    text = export_text(lang, precision) if lang != "mtlx" else export_files(lang, "eon.mtlx")[1][1]
    head = text.split("\n\n", 1)[0] if lang != "cpp" else text[: text.index("#ifndef")]
    for needed in (
        "normal +z",
        "wi towards the light",
        "wo towards the viewer",
        "without the cosine",
        "r in [0, 1]",
        "JCGT) 14(1), 2025",
        "Apache-2.0",
        f"openpbr-diffuse {od.__version__}",
        "Passed:",
        "Precision",
    ):
        assert needed in " ".join(head.replace("//", " ").split()), needed
    assert len([ln for ln in text.splitlines() if ln.startswith("// grade: ")]) == 1
    assert grade_command(lang) in text


def test_the_neutral_source_holds_no_hand_copied_constant():
    # every constant is a {KEY} filled from the package's modules; the only literals left are
    # small exact numbers of the formulas (0.5, 2/3, QON's 0.33, 0.45, 0.09) and P_u's exponent 0.1
    for line in neutral_source().splitlines():
        if line.startswith("const real"):
            assert re.fullmatch(r"const real EON_\w+ = \{\w+\};(\s*//.*)?", line), line
    code = "\n".join(ln.split("//")[0] for ln in neutral_source().splitlines())
    assert set(re.findall(r"\d+\.\d+", code)) <= {"0.0", "1.0", "2.0", "3.0", "0.5", "0.1", "0.33", "0.45", "0.09"}


def test_changing_a_constant_of_the_package_changes_every_export(monkeypatch, tmp_path):
    from openpbr_diffuse.models import fon

    before = {k: _full(*k) for k in ALL}
    monkeypatch.setattr(fon, "C1", fon.C1 * 1.05)
    after = {k: _full(*k) for k in ALL}
    for k in ALL:
        assert before[k] != after[k], k
        assert repr(fon.C1) in after[k]
    if not available("glm"):  # the compiled half needs g++ and GLM
        return
    path = tmp_path / "eon.cpp"
    path.write_text(after[("cpp", "float")])
    run = subprocess.run(_grade_argv(path, "cpp") + ["--quick"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "DOES NOT CONFORM" in run.stdout.upper()


@requires("glm")
@pytest.mark.parametrize("precision", ["float", "double"])
def test_cpp_export_passes_its_grade_line(tmp_path, precision):
    path = write_export("cpp", tmp_path / "eon.cpp", precision=precision)
    run = subprocess.run(_grade_argv(path, "cpp") + ["--quick"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "CONFORMS" in run.stdout and "[pass] sampler_pdf.reference" in run.stdout


@requires("gl")
def test_glsl_export_passes_its_grade_line(tmp_path):
    path = write_export("glsl", tmp_path / "eon.glsl")
    run = subprocess.run(_grade_argv(path, "glsl") + ["--quick"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "CONFORMS" in run.stdout and "[pass] sampler_pdf.reference" in run.stdout


@requires("vulkan")
def test_wgsl_export_passes_its_grade_line(tmp_path):
    path = write_export("wgsl", tmp_path / "eon.wgsl")
    run = subprocess.run(_grade_argv(path, "wgsl"), capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "wgsl:eon.wgsl:eon_f: CONFORMS" in run.stdout and "result: conforms" in run.stdout


@requires("vulkan")
def test_wgsl_with_roughness_squared_does_not_conform_and_is_named(tmp_path):
    text = export_text("wgsl")
    call = "return eon_lobe(wi, wo, roughness, rho, false, false);"
    assert text.count(call) == 1
    path = tmp_path / "squared.wgsl"
    path.write_text(text.replace(call, "return eon_lobe(wi, wo, roughness * roughness, rho, false, false);"))
    run = subprocess.run(_grade_argv(path, "wgsl"), capture_output=True, text=True, timeout=300)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "DOES NOT CONFORM" in run.stdout and "roughness_squared" in run.stdout


@requires("vulkan")
def test_check_wgsl_names_a_missing_function_and_code_that_does_not_compile(tmp_path):
    path = write_export("wgsl", tmp_path / "eon.wgsl")
    run = _cli("check", "--wgsl", str(path), "--function", "eon_g")
    assert run.returncode == 2 and run.stderr.strip().splitlines() == [
        f"openpbr-diffuse check: error: no function eon_g(...) in {path}"
    ], run.stderr
    bad = tmp_path / "bad.wgsl"
    bad.write_text("fn f(wi: vec3<f32>, wo: vec3<f32>, r: f32, rho: vec3<f32>) -> vec3<f32> { return rho * 1.0.x; }\n")
    run = _cli("check", "--wgsl", str(bad), "--function", "f")
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1, run.stderr
    assert "Traceback" not in run.stderr and "WGSL" in run.stderr


@pytest.mark.slow
@requires("gl")
def test_glsl_export_passes_its_grade_line_as_written(tmp_path):
    path = write_export("glsl", tmp_path / "eon.glsl")
    run = subprocess.run(_grade_argv(path, "glsl"), capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr


# ---- the variants and the edges, against the library ----


def _cases():
    """(wi, wo, r, rho) rows: random pairs and the edges mu = 0, r = 0, rho = 0 and 1, s < 0, the normal."""
    rng = np.random.default_rng(7)

    def hemi(n):
        v = rng.normal(size=(n, 3))
        v[:, 2] = np.abs(v[:, 2])
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    n = 64
    wi, wo = hemi(n), hemi(n)
    r = rng.uniform(0, 1, n)
    rho = rng.uniform(0, 1, (n, 3))
    edges_w = [
        ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),  # mu_i = 0
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),  # mu_o = 0
        ([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]),  # both grazing, opposite
        ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),  # the normal
        ([0.6, 0.0, 0.8], [-0.6, 0.0, 0.8]),  # s < 0
    ]
    rows = []
    for a, b in edges_w:
        for rr in (0.0, 0.5, 1.0):
            for p in ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.0, 0.5, 1.0]):
                rows.append((a, b, rr, p))
    wi = np.vstack([wi, [x[0] for x in rows]])
    wo = np.vstack([wo, [x[1] for x in rows]])
    r = np.concatenate([r, [x[2] for x in rows]])
    rho = np.vstack([rho, [x[3] for x in rows]])
    return wi, wo, r, rho


def _expected(wi, wo, r, rho):
    """Columns: f, f_fit, f_white_tint, albedo(wo.z), albedo_fit, albedo_white_tint, average, fon, qon, lambert (3 each), pdf."""
    mu = wo[:, 2]
    cols = [
        od.evaluate("eon", wi, wo, r, rho),
        od.evaluate("eon_approx", wi, wo, r, rho),
        od.evaluate("eon", wi, wo, r, rho, color_mode="white_tint"),
        od.directional_albedo("eon", mu, r, rho),
        od.directional_albedo("eon_approx", mu, r, rho),
        od.directional_albedo("eon", mu, r, rho, color_mode="white_tint"),
        od.average_albedo("eon", r, rho),
        od.evaluate("fon", wi, wo, r, rho),
        od.evaluate("qon", wi, wo, r, rho),
        od.evaluate("lambert", wi, wo, r, rho),
    ]
    p = np.where((wo[:, 2] > 0) & (wi[:, 2] > 0), od.pdf("eon", wo, wi, r), 0.0)
    return np.hstack([*cols, p[:, None]])


_CPP_MAIN = r"""
#include <cstdio>
int main() {
    double v[10];
    while (std::scanf("%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", v, v + 1, v + 2, v + 3, v + 4, v + 5, v + 6, v + 7, v + 8, v + 9) == 10) {
        eon_vec3 wi = eon_vec3_make(v[0], v[1], v[2]), wo = eon_vec3_make(v[3], v[4], v[5]);
        eon_real r = v[6];
        eon_vec3 rho = eon_vec3_make(v[7], v[8], v[9]);
        eon_vec3 out[10] = {eon_f(wi, wo, r, rho), eon_f_fit(wi, wo, r, rho), eon_f_white_tint(wi, wo, r, rho),
            eon_albedo(wo.z, r, rho), eon_albedo_fit(wo.z, r, rho), eon_albedo_white_tint(wo.z, r, rho),
            eon_average_albedo(r, rho), eon_fon_f(wi, wo, r, rho), eon_qon_f(wi, wo, r, rho), eon_lambert_f(wi, wo, rho)};
        for (int k = 0; k < 10; ++k) std::printf("%.17g %.17g %.17g ", (double)out[k].x, (double)out[k].y, (double)out[k].z);
        std::printf("%.17g\n", (double)eon_pdf(wo, wi, r));
    }
}
"""


def _check(got, want, precision):
    rel, ab = BOUND[precision]
    assert np.all(np.isfinite(got))
    err = np.abs(got - want) - (ab + rel * np.abs(want))
    worst = np.unravel_index(np.argmax(err), err.shape)
    assert err.max() <= 0, f"column {worst[1]} row {worst[0]}: {got[worst]} vs {want[worst]}"


@requires("glm")
@pytest.mark.parametrize("precision", ["float", "double"])
def test_cpp_export_matches_the_library_within_its_stated_precision_and_is_finite_at_the_edges(tmp_path, precision):
    src = tmp_path / "run.cpp"
    src.write_text(export_text("cpp", precision) + _CPP_MAIN)
    exe = tmp_path / "run"
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Werror", str(src), "-o", str(exe)], check=True, timeout=120)
    wi, wo, r, rho = _cases()
    if precision == "float":  # the inputs as the float32 code sees them
        wi, wo, r, rho = (x.astype(np.float32).astype(np.float64) for x in (wi, wo, r, rho))
    lines = "\n".join(" ".join(repr(float(x)) for x in row) for row in np.hstack([wi, wo, r[:, None], rho]))
    run = subprocess.run([str(exe)], input=lines, capture_output=True, text=True, timeout=60, check=True)
    got = np.array([[float(x) for x in ln.split()] for ln in run.stdout.splitlines()])
    _check(got, _expected(wi, wo, r, rho), precision)


#: a CUDA kernel calling the C++ export's eon_f on the device (EON_HOST_DEVICE is __host__ __device__ under nvcc)
_CUDA_KERNEL = """
__global__ void eon_kernel(const float* in, float* out, int n) {
    int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const float* x = in + 10 * i;
    eon_vec3 f = eon_f(eon_vec3_make(x[0], x[1], x[2]), eon_vec3_make(x[3], x[4], x[5]), x[6],
                       eon_vec3_make(x[7], x[8], x[9]));
    out[3 * i] = f.x; out[3 * i + 1] = f.y; out[3 * i + 2] = f.z;
}
"""


@pytest.mark.parametrize("precision", ["float", "double"])
def test_cpp_export_compiles_as_cuda_device_code(tmp_path, precision):
    import shutil

    nvcc = shutil.which("nvcc") or ("/usr/local/cuda/bin/nvcc" if Path("/usr/local/cuda/bin/nvcc").exists() else None)
    if nvcc is None:  # CUDA is not installed in CI: the test runs where it is
        pytest.skip("nvcc not installed")
    src = tmp_path / "eon.cu"
    src.write_text(export_text("cpp", precision) + _CUDA_KERNEL)
    run = subprocess.run(
        [nvcc, "-x", "cu", "-std=c++17", "-Werror", "all-warnings", "-c", "-o", "/dev/null", str(src)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr


@requires("vulkan")
def test_wgsl_export_runs_through_wgpu_and_matches_the_library(tmp_path):
    from openpbr_diffuse.graders.babylon import _run_wgsl

    main = """
@group(0) @binding(0) var<storage, read> grader_in: array<f32>;
@group(0) @binding(1) var<storage, read_write> grader_out: array<f32>;
@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) gid: vec3u) {
    let k = gid.x * 10u;
    let wi = vec3<f32>(grader_in[k], grader_in[k + 1u], grader_in[k + 2u]);
    let wo = vec3<f32>(grader_in[k + 3u], grader_in[k + 4u], grader_in[k + 5u]);
    let r = grader_in[k + 6u];
    let rho = vec3<f32>(grader_in[k + 7u], grader_in[k + 8u], grader_in[k + 9u]);
    var out = array<vec3<f32>, 10>(eon_f(wi, wo, r, rho), eon_f_fit(wi, wo, r, rho), eon_f_white_tint(wi, wo, r, rho),
        eon_albedo(wo.z, r, rho), eon_albedo_fit(wo.z, r, rho), eon_albedo_white_tint(wo.z, r, rho),
        eon_average_albedo(r, rho), eon_fon_f(wi, wo, r, rho), eon_qon_f(wi, wo, r, rho), eon_lambert_f(wi, wo, rho));
    let o = gid.x * 31u;
    for (var j = 0u; j < 10u; j++) {
        grader_out[o + 3u * j] = out[j].x; grader_out[o + 3u * j + 1u] = out[j].y; grader_out[o + 3u * j + 2u] = out[j].z;
    }
    grader_out[o + 30u] = eon_pdf(wo, wi, r);
}
"""
    wi, wo, r, rho = (x.astype(np.float32).astype(np.float64) for x in _cases())
    got = _run_wgsl(export_text("wgsl") + main, np.hstack([wi, wo, r[:, None], rho]), 31, "WGSL export").astype(
        np.float64
    )
    # GPU float32 (lavapipe's acos, pow, cos and sin within a few ulp): the float bound, loosened 5x
    rel, ab = BOUND["float"]
    want = _expected(wi, wo, r, rho)
    assert np.all(np.isfinite(got))
    assert np.all(np.abs(got - want) <= 5 * (ab + rel * np.abs(want)))


def test_osl_export_uses_only_what_osl_has():
    # the rendering rules OSL needs, on the text (compiled and run by Cycles: the slow test below)
    text = export_text("osl")
    code = "\n".join(ln.split("//")[0] for ln in text.splitlines())
    assert not re.search(r"\b(bool|vec3|eon_real|std::|true|false)\b", code)
    assert not re.search(r"\b[A-Za-z_]\w*\.[xyz]\b", code)  # components as v[0], v[1], v[2]
    assert code.count("{") == code.count("}") and code.count("(") == code.count(")")
    assert "shader eon_diffuse(" in code and "#define EON_C1 " in code


# ---- the command ----


def test_cli_writes_refuses_existing_and_symlinks_and_double_outside_cpp(tmp_path):
    out = tmp_path / "eon.wgsl"
    run = _cli("export", "--lang", "wgsl", "--out", str(out))
    assert run.returncode == 0 and out.read_text() == export_text("wgsl")
    out.write_text("mine")
    run = _cli("export", "--lang", "wgsl", "--out", str(out))
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1 and out.read_text() == "mine"
    assert _cli("export", "--lang", "wgsl", "--out", str(out), "--force").returncode == 0
    assert out.read_text() == export_text("wgsl")
    link = tmp_path / "link.cpp"
    link.symlink_to(out)
    run = _cli("export", "--lang", "cpp", "--out", str(link), "--force")
    assert run.returncode == 2 and "symbolic link" in run.stderr and out.read_text() == export_text("wgsl")
    run = _cli("export", "--lang", "glsl", "--precision", "double", "--out", str(tmp_path / "d.glsl"))
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1 and "cpp only" in run.stderr
    assert not (tmp_path / "d.glsl").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eon.wgsl", "link.cpp"]  # no temporary left


# ---- MaterialX: the nodedef loads, MaterialX's own GLSL generator emits EON, the result compiles ----

_MX_MATERIAL = """
import sys
import MaterialX as mx
from MaterialX import PyMaterialXGenGlsl as gg, PyMaterialXGenShader as gs

doc = mx.createDocument()
mx.readFromXmlFile(doc, sys.argv[1])
lib = mx.createDocument()
search = mx.getDefaultDataSearchPath()
mx.loadLibraries(mx.getDefaultDataLibraryFolders(), search, lib)
doc.importLibrary(lib)
bsdf = doc.addNode("openpbr_diffuse_eon_bsdf", "eon1", "BSDF")
bsdf.setInputValue("roughness", 0.5)
surface = doc.addNode("surface", "surface1", "surfaceshader")
surface.setConnectedNode("bsdf", bsdf)
doc.addMaterialNode("material1", surface)
generator = gg.GlslShaderGenerator.create()
context = gs.GenContext(generator)
context.registerSourceCodeSearchPath(search)
shader = generator.generate("material1", surface, context)
open(sys.argv[2], "w").write(shader.getSourceCode(gs.VERTEX_STAGE))
open(sys.argv[3], "w").write(shader.getSourceCode(gs.PIXEL_STAGE))
print(doc.validate()[0])
"""
_GL_COMPILE = """
import sys
from openpbr_diffuse.graders.glsl import gl_context
program = gl_context().program(vertex_shader=open(sys.argv[1]).read(), fragment_shader=open(sys.argv[2]).read())
print(sorted(name for name in program._members if name.startswith("eon1_")))
"""


@pytest.fixture(scope="module")
def mtlx_shader(tmp_path_factory):
    """The .mtlx export, and the GLSL MaterialX generates for a material using its node (run
    from another folder: the implementation file is found beside the document)."""
    tmp = tmp_path_factory.mktemp("mtlx")
    out = tmp / "out"
    out.mkdir()
    path = write_export("mtlx", out / "eon.mtlx")
    vs, ps = tmp / "vs.glsl", tmp / "ps.glsl"
    run = subprocess.run(
        [sys.executable, "-c", _MX_MATERIAL, str(path), str(vs), str(ps)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp,
    )
    assert run.returncode == 0, run.stderr
    return path, run.stdout.split(), vs, ps


def test_mtlx_export_writes_the_document_and_its_implementation_beside_it(tmp_path):
    path = write_export("mtlx", tmp_path / "lobe.mtlx")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lobe.mtlx", "lobe_genglsl.glsl"]
    assert 'file="lobe_genglsl.glsl"' in path.read_text()
    glsl = (tmp_path / "lobe_genglsl.glsl").read_text()
    assert export_text("glsl").split("\n// grade: ")[1].split("\n", 1)[1] in glsl  # the GLSL functions, verbatim
    assert "// grade: none" in glsl and "JCGT) 14(1), 2025" in glsl
    (tmp_path / "lobe_genglsl.glsl").write_text("mine")
    run = _cli("export", "--lang", "mtlx", "--out", str(tmp_path / "lobe.mtlx"), "--force")
    assert run.returncode == 0 and (tmp_path / "lobe_genglsl.glsl").read_text() == glsl
    other = tmp_path / "other.mtlx"
    (tmp_path / "other_genglsl.glsl").write_text("mine")  # an existing sibling: nothing written
    run = _cli("export", "--lang", "mtlx", "--out", str(other))
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1 and not other.exists()
    assert (tmp_path / "other_genglsl.glsl").read_text() == "mine"


def test_mtlx_nodedef_validates_and_materialx_emits_the_eon_functions(mtlx_shader):
    _, valid, _, ps = mtlx_shader
    assert valid == ["True"]  # with MaterialX's libraries (the BSDF type is theirs)
    text = ps.read_text()
    for sig in (
        "vec3 eon_f(vec3 wi, vec3 wo, float roughness, vec3 rho)",
        "vec3 eon_albedo(float mu",
        "void mx_openpbr_diffuse_eon_bsdf(",
    ):
        assert text.count(sig) == 1, sig
    assert re.search(r"mx_openpbr_diffuse_eon_bsdf\(closureData, eon1_weight", text)  # the node's call


@requires("gl")
def test_mtlx_generated_glsl_compiles_on_llvmpipe(mtlx_shader):
    _, _, vs, ps = mtlx_shader
    run = subprocess.run(
        [sys.executable, "-c", _GL_COMPILE, str(vs), str(ps)], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert "eon1_roughness" in run.stdout and "eon1_color" in run.stdout


@requires("gl")
def test_mtlx_generated_eon_functions_pass_check_glsl(mtlx_shader, tmp_path):
    # the EON functions as MaterialX's generator emitted them, graded like the GLSL export
    _, _, _, ps = mtlx_shader
    text = ps.read_text()
    start = text.index("float eon_sel(bool c")
    end = text.index("\n", text.index("vec3 eon_sample_wi(vec3 wo, vec2 u, float roughness)"))
    path = tmp_path / "generated.glsl"
    path.write_text(text[start:end] + "\n")
    argv = grade_command("glsl", str(path)).split()
    run = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", *argv[1:], "--quick"], capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "CONFORMS" in run.stdout


# ---- OSL: compiled by Cycles' oslc and run in a Script node (Blender's bpy in its own Python) ----

#: (columns of _expected) x (rows): the harness image holds 11 groups of 11 x 11 pixels
_OSL_SIDE = 11
_OSL_OUTPUTS = (
    "eon_f(wi, wo, r, rho)",
    "eon_f_fit(wi, wo, r, rho)",
    "eon_f_white_tint(wi, wo, r, rho)",
    "eon_albedo(wo[2], r, rho)",
    "eon_albedo_fit(wo[2], r, rho)",
    "eon_albedo_white_tint(wo[2], r, rho)",
    "eon_average_albedo(r, rho)",
    "eon_fon_f(wi, wo, r, rho)",
    "eon_qon_f(wi, wo, r, rho)",
    "eon_lambert_f(wi, wo, rho)",
    "vector(eon_pdf(wo, wi, r), 0, 0)",
)


def _osl_harness(rows):
    """The OSL export's functions (its shader left out: one shader per file) and a shader whose
    pixel (i, j) outputs group i // 11 of row (i % 11) + 11 j."""
    text = export_text("osl")
    funcs = text[: text.index("\n// The lobe at this shading point")]
    n, side, groups = len(rows), _OSL_SIDE, len(_OSL_OUTPUTS)
    values = ", ".join(repr(float(x)) for x in rows.ravel())
    picks = "\n".join(f"    if (g == {k}) res = {call};" for k, call in enumerate(_OSL_OUTPUTS))
    return (
        funcs
        + f"""
shader eon_harness(output color value = 0)
{{
    float IN[{rows.size}] = {{ {values} }};
    int i = (int) floor((P[0] + {0.5 * groups}) * {side});
    int j = (int) floor((P[1] + 0.5) * {side});
    i = min(max(i, 0), {side * groups - 1});
    int g = i / {side};
    int k = 10 * min((i - g * {side}) + {side} * min(max(j, 0), {side - 1}), {n - 1});
    vector wi = vector(IN[k], IN[k + 1], IN[k + 2]);
    vector wo = vector(IN[k + 3], IN[k + 4], IN[k + 5]);
    float r = IN[k + 6];
    vector rho = vector(IN[k + 7], IN[k + 8], IN[k + 9]);
    vector res = vector(0);
{picks}
    value = color(res[0], res[1], res[2]);
}}
"""
    )


@pytest.mark.slow
@requires("bpy")
def test_osl_export_compiles_in_cycles_and_matches_the_library(tmp_path):
    from openpbr_diffuse.graders import cycles, limits

    wi, wo, r, rho = (x.astype(np.float32).astype(np.float64) for x in _cases())
    rows = np.hstack([wi, wo, r[:, None], rho])
    assert len(rows) <= _OSL_SIDE**2
    harness, shader = tmp_path / "harness.osl", tmp_path / "eon.osl"
    harness.write_text(_osl_harness(rows))
    write_export("osl", shader)
    mu_o = 0.6
    scene = Path(__file__).with_name("_cycles_osl_scene.py")
    argv = [cycles.bpy_python(), str(scene), str(harness), str(shader), str(tmp_path / "out")]
    argv += [str(_OSL_SIDE * len(_OSL_OUTPUTS)), str(_OSL_SIDE), str(mu_o)]
    run = limits.run_limited(argv, label="Cycles OSL render", timeout=300)
    assert run.returncode == 0, run.stderr.decode()[-3000:]
    data = np.load(tmp_path / "out.npz")
    img = data["harness"].astype(np.float64)  # (side, side * groups, 3)
    got = np.zeros((len(rows), 33))
    for k in range(len(rows)):
        i, j = k % _OSL_SIDE, k // _OSL_SIDE
        got[k] = np.concatenate([img[j, g * _OSL_SIDE + i] for g in range(len(_OSL_OUTPUTS))])
    got = got[:, :31]  # the pdf group's last two channels are 0
    want = _expected(wi, wo, r, rho)
    rel, ab = BOUND["float"]  # Cycles' OSL float32 on the CPU, its transcendental functions: 5x looser
    assert np.all(np.isfinite(got))
    err = np.abs(got - want) - 5 * (ab + rel * np.abs(want))
    assert err.max() <= 0, np.unravel_index(np.argmax(err), err.shape)
    # the export's shader eon_diffuse itself, seen along wo = (0, -0.8, 0.6), light along the normal
    # (wi_local's default): f_value = f(n, wo), the same at every azimuth of the tangent frame
    assert list(data["shader_outputs"]) == ["f_value", "albedo_value"]
    wo_view = np.array([[0.0, -np.sqrt(1 - mu_o**2), mu_o]])
    f_n = od.evaluate("eon", np.array([[0.0, 0.0, 1.0]]), wo_view, 0.5, [0.8, 0.8, 0.8])[0]
    shade = data["shader"].reshape(-1, 3).astype(np.float64)
    assert np.all(np.abs(shade - f_n) <= 5 * (ab + rel * f_n)), (shade[0], f_n)
