"""Run C++ functions: a harness compiled at run time with g++ -std=c++17, cached by source hash.

The harness includes the subject's headers unchanged and defines one entry point per graded
function; it reads rows of float32 inputs on stdin and writes float32 outputs on stdout.  The
binary is cached under ``$OPENPBR_DIFFUSE_CACHE`` (default ``~/.cache/openpbr-diffuse``), keyed
by the SHA-256 of the harness text, the subject's sources, the compiler's version and flags, so
a second run with unchanged sources does not recompile.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import limits
from .errors import GraderUnavailable

FLAGS = ("-std=c++17", "-O2")


def cache_dir() -> Path:
    root = os.environ.get("OPENPBR_DIFFUSE_CACHE") or Path.home() / ".cache" / "openpbr-diffuse"
    return Path(root) / "graders"


def compiler() -> str:
    """Path of the C++ compiler ($CXX, else g++)."""
    name = os.environ.get("CXX", "g++")
    path = shutil.which(name)
    if path is None:
        raise GraderUnavailable(f"no C++ compiler ({name}) found: apt-get install g++ (or set CXX)")
    return path


def compiler_version() -> str:
    out = subprocess.run([compiler(), "--version"], capture_output=True, text=True, check=False)
    return out.stdout.splitlines()[0] if out.stdout else "unknown"


@dataclass
class Entry:
    """One entry point: ``n_in`` floats in, ``n_out`` out; ``body`` reads ``in[k]``, writes ``out[k]``."""

    n_in: int
    n_out: int
    body: str


@dataclass
class Harness:
    """A C++ program around the subject's code: ``prelude`` (its includes) + entry points."""

    prelude: str
    entries: dict[str, Entry]
    include_dirs: list = field(default_factory=list)
    defines: dict = field(default_factory=dict)
    sources: list = field(default_factory=list)  # the subject's files, hashed into the cache key
    label: str = "C++ source"

    def text(self) -> str:
        parts = [self.prelude, "\n#include <cstdio>\n#include <cstring>\n#include <vector>\n"]
        for name, e in self.entries.items():
            parts.append(f"static void grader_{name}(const float* in, float* out) {{\n{e.body}\n}}\n")
        parts.append(
            "int main(int argc, char** argv) {\n"
            "    if (argc < 2) return 64;\n"
            "    int n_in = 0, n_out = 0; void (*fn)(const float*, float*) = nullptr;\n"
        )
        for name, e in self.entries.items():
            parts.append(
                f'    if (!std::strcmp(argv[1], "{name}")) {{ n_in = {e.n_in}; n_out = {e.n_out}; '
                f"fn = grader_{name}; }}\n"
            )
        parts.append(
            "    if (!fn) return 65;\n"
            "    std::vector<float> in(n_in), out(n_out);\n"
            "    while (std::fread(in.data(), sizeof(float), n_in, stdin) == (size_t)n_in) {\n"
            "        for (int k = 0; k < n_out; ++k) out[k] = 0.0f;\n"
            "        fn(in.data(), out.data());\n"
            "        std::fwrite(out.data(), sizeof(float), n_out, stdout);\n"
            "    }\n    return 0;\n}\n"
        )
        return "".join(parts)

    def _key(self, text: str) -> str:
        h = hashlib.sha256(text.encode())
        for f in self.sources:
            h.update(str(f).encode())
            h.update(Path(f).read_bytes())
        h.update(
            " ".join((*FLAGS, *map(str, self.include_dirs), *(f"{k}={v}" for k, v in self.defines.items()))).encode()
        )
        h.update(compiler_version().encode())
        return h.hexdigest()[:24]

    def binary(self) -> Path:
        """Compile (or reuse the cached build of) the harness; returns the executable's path."""
        text = self.text()
        exe = cache_dir() / f"harness-{self._key(text)}"
        if exe.is_file():
            return exe
        exe.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            src = Path(tmp) / "harness.cpp"
            src.write_text(text)
            cmd = [
                compiler(),
                *FLAGS,
                *(f"-I{d}" for d in self.include_dirs),
                *(f"-D{k}={v}" for k, v in self.defines.items()),
                str(src),
                "-o",
                str(Path(tmp) / "a.out"),
            ]
            run = limits.run_limited(cmd, label=f"compiling {self.label}")
            if run.returncode != 0:
                err = run.stderr.decode(errors="replace")
                if limits.memory_message(err) or run.returncode < 0:
                    raise GraderUnavailable(
                        limits.memory_failure(f"compiling {self.label}", Path(compiler()).name, run.returncode)
                    )
                if "glm/glm.hpp" in err and "No such file" in err:
                    raise GraderUnavailable(
                        "GLM headers not found (glm/glm.hpp): apt-get install libglm-dev "
                        "(or pass --include DIR holding glm/)"
                    )
                first = next((line for line in err.splitlines() if "error" in line), err.strip()[:300])
                raise GraderUnavailable(f"{self.label} does not compile with {Path(compiler()).name}: {first.strip()}")
            # move into place atomically so parallel runs never execute a half-written file
            tmp_exe = exe.with_suffix(f".tmp{os.getpid()}")
            shutil.move(str(Path(tmp) / "a.out"), tmp_exe)
            os.replace(tmp_exe, exe)
        return exe

    def run(self, name: str, inputs: np.ndarray) -> np.ndarray:
        """Run entry ``name`` on rows of ``inputs``; returns (rows, n_out) float32."""
        e = self.entries[name]
        inputs = np.ascontiguousarray(inputs, dtype=np.float32).reshape(-1, e.n_in)
        run = limits.run_limited(
            [str(self.binary()), name], input=inputs.tobytes(), label=f"{self.label} (harness entry {name})"
        )
        if run.returncode != 0:
            if (limits.memory_message(run.stderr) or run.returncode < 0) and limits.memory_in_force() < limits.MEMORY:
                raise GraderUnavailable(
                    limits.memory_failure(f"{self.label} (harness entry {name})", "the compiled code", run.returncode)
                )
            raise GraderUnavailable(
                f"{self.label}: harness entry {name} exited with status "
                f"{run.returncode}: {run.stderr.decode(errors='replace').strip()[:200]}"
            )
        out = np.frombuffer(run.stdout, dtype=np.float32)
        if out.size != inputs.shape[0] * e.n_out:
            raise GraderUnavailable(
                f"{self.label}: harness entry {name} wrote {out.size} values, expected {inputs.shape[0] * e.n_out}"
            )
        return out.reshape(-1, e.n_out).copy()


def sampler_entries(sample_function: str, pdf_function: str) -> dict[str, Entry]:
    """Harness entries ``sample`` (wo, u, roughness -> wi, pdf(wi)) and ``pdf`` (wo, wi, roughness).

    The C++ signatures (any types constructible from these arguments, indexable with [0..2])::

        glm::vec3 SAMPLE(glm::vec3 wo, glm::vec2 u, float roughness);
        float     PDF(glm::vec3 wo, glm::vec3 wi, float roughness);

    Examples
    --------
    >>> sorted(sampler_entries("sample_wi", "pdf"))
    ['pdf', 'sample']
    """
    return {
        "sample": Entry(
            6,
            4,
            f"""
    const glm::vec3 grader_wo(in[0], in[1], in[2]);
    const auto grader_wi = {sample_function}(grader_wo, glm::vec2(in[3], in[4]), in[5]);
    out[0] = grader_wi[0]; out[1] = grader_wi[1]; out[2] = grader_wi[2];
    out[3] = {pdf_function}(grader_wo, glm::vec3(grader_wi[0], grader_wi[1], grader_wi[2]), in[5]);""",
        ),
        "pdf": Entry(
            7,
            1,
            f"""
    out[0] = {pdf_function}(glm::vec3(in[0], in[1], in[2]), glm::vec3(in[3], in[4], in[5]), in[6]);""",
        ),
    }


def sampler_functions(harness: Harness) -> tuple[Callable[..., Any], Callable[..., Any]]:
    """``(sample, pdf)`` array functions running a harness's :func:`sampler_entries`
    (the same calling convention as :func:`.glsl.sampler_functions`)."""
    from ._arrays import rows

    def sample(wo, roughness, u):
        out = harness.run("sample", rows(wo, u, roughness))
        return out[:, :3], out[:, 3]

    def pdf(wo, wi, roughness):
        return harness.run("pdf", rows(wo, wi, roughness))[:, 0]

    return sample, pdf
