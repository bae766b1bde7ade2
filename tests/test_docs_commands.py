"""Every command in the documentation runs.

The fenced ``bash``, ``console`` and ``python`` blocks of ``README.md`` and ``docs/**/*.md`` are
read; each ``openpbr-diffuse ...`` line becomes a test that runs it (``python -m
openpbr_diffuse ...``) and expects exit status 0, or the status a ``# exits N`` comment on the
line states; each Python block becomes a test that executes it and expects no exception.  A
page's snippets run in order in one scratch folder of their own (its Python blocks share one
namespace, as a reader's session would), where ``materials/`` and ``tests/subjects/`` are the
repository's: a command may use those files and the files an earlier snippet of the same page
writes.  A test first runs the earlier snippets of its page that write files (Python blocks,
commands with ``--out``, ``--junit`` or ``--image``), so each test also runs alone (``-k``).

Commands that cannot run here (installers, the test runner, a Dask cluster, benchmarks) are in
:data:`SKIP`; expensive ones (compiling and grading code, simulations, full reports) are in
:data:`SLOW` and run with ``-m slow``.  Both lists are checked against the pages, so an entry
whose command left the documentation fails.  Any other shell command fails: document
``openpbr-diffuse`` or ``python tools/NAME.py`` commands, or add the line to :data:`SKIP` with
the reason.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LANGUAGES = ("bash", "console", "python")
#: Options whose command writes a file a later snippet may read.
WRITERS = ("--out", "--junit", "--image", "--expected-image", "--jsonl")
TIMEOUT = 1800

#: (page, text the command contains, why it does not run here).
SKIP = [
    ("README.md", "pip install -e '.[test]'", "installs the package (and then runs the full report)"),
    ("docs/index.md", "pip install -e '.[test]'", "installs the package (and then runs the full report)"),
    ("README.md", "pytest", "the test suite itself"),
    ("docs/index.md", "pytest", "the test suite itself"),
    ("docs/design/launcher.md", "pytest -m cpu_portable", "the test suite itself, under an older CPU target"),
    ("docs/benchmarks/bench.md", "python tools/bench", "a benchmark: minutes of timing, its output is the dated table"),
    ("docs/guide/graded-implementations.md", "pip install bpy", "creates a virtual environment and installs bpy"),
    ("docs/guide/graded-implementations.md", "npm install", "installs Babylon.js from the npm registry"),
    ("docs/guide/graded-implementations.md", "--implementation cycles", "needs a Python with bpy"),
    ("docs/guide/simulation.md", "--scheduler tcp://", "needs a Dask cluster"),
    (
        "docs/guide/renderer-conformance.md",
        "python tools/renderer_conformance.py",
        "rewrites this page from fresh renders (tests/test_renderers.py asserts each verdict)",
    ),
]

#: (page, text the command or block contains, why it is run with ``-m slow`` only).
SLOW = [
    ("docs/guide/conformance.md", "check --glsl", "compiles and grades GLSL on llvmpipe (10-15 s)"),
    ("docs/guide/conformance.md", "check --cpp", "compiles and grades C++ (5-10 s)"),
    ("docs/guide/conformance.md", "report --glsl", "a report with an implementation"),
    ("docs/guide/graded-implementations.md", "check --implementation materialx", "runs MaterialX's GLSL"),
    ("docs/guide/graded-implementations.md", "check --glsl", "compiles and grades GLSL on llvmpipe"),
    ("docs/guide/graded-implementations.md", "check --cpp", "compiles and grades C++"),
    ("docs/guide/graded-implementations.md", "--implementation babylonjs", "runs Babylon.js's shaders (~17 s)"),
    ("docs/guide/report.md", "report --glsl", "a report with an implementation"),
    ("docs/guide/report.md", "report --cpp", "a report with an implementation"),
    ("docs/guide/report.md", "report --implementation", "a report with an implementation"),
    ("docs/guide/report.md", "report --quick", "the quick report: every evidence section"),
    ("docs/guide/report.md", "report --select", "runs two sections of the report"),
    ("docs/guide/simulation.md", "simulate", "Monte Carlo simulations of the microsurface"),
    ("docs/guide/chart.md", "check --implementation eevee", "renders the chart with Blender EEVEE (bpy, EGL)"),
    ("docs/guide/layered.md", "simulate_layered_albedo", "a Monte Carlo simulation of 10^6 paths"),
]


@dataclass
class Snippet:
    """One command line or one Python block of a page."""

    page: str
    line: int
    kind: str  # "python", "cli" (openpbr-diffuse), "tool" (python tools/NAME.py) or "shell"
    text: str
    expect: int = 0
    skip: str | None = None
    slow: str | None = None

    @property
    def id(self) -> str:
        return f"{self.page}:{self.line}"

    @property
    def writes(self) -> bool:
        if self.kind == "python":
            return True
        return self.kind in ("cli", "tool") and any(
            t.split("=")[0] in WRITERS for t in shlex.split(self.text, comments=True)
        )


def _fenced_blocks(text: str):
    """(language, first line number of the body, body lines) of each fenced block."""
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^(\s*)```\s*([\w+-]*)", lines[i])
        if not m:
            i += 1
            continue
        indent, lang = len(m.group(1)), m.group(2).lower()
        body, j = [], i + 1
        while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
            body.append(lines[j][indent:] if lines[j][:indent].strip() == "" else lines[j])
            j += 1
        yield lang, i + 2, body
        i = j + 1


def _command_lines(lang: str, start: int, body: list[str]):
    """(line number, command) of a bash or console block, continuation lines joined."""
    k = 0
    while k < len(body):
        line, first = body[k], start + k
        k += 1
        if lang == "console":
            if not line.startswith("$ "):
                continue  # output
            line = line[2:]
        while line.rstrip().endswith("\\") and k < len(body):
            line = line.rstrip()[:-1] + " " + body[k].strip()
            k += 1
        if line.strip() and not line.lstrip().startswith("#"):
            yield first, line.strip()


def _expected_status(line: str) -> int:
    m = re.search(r"#.*\bexits (\d+)", line)
    return int(m.group(1)) if m else 0


def _classify(s: Snippet) -> Snippet:
    for page, needle, why in SKIP:
        if page == s.page and needle in s.text:
            s.skip = why
    for page, needle, why in SLOW:
        if page == s.page and needle in s.text:
            s.slow = why
    if s.kind == "cli" and shlex.split(s.text, comments=True) == ["openpbr-diffuse", "report"]:
        s.slow = "the full report: every evidence section"
    return s


def collect() -> dict[str, list[Snippet]]:
    """{page: its snippets in order} for every page with a runnable block."""
    out: dict[str, list[Snippet]] = {}
    for path in PAGES:
        page = path.relative_to(ROOT).as_posix()
        snippets = []
        for lang, start, body in _fenced_blocks(path.read_text(encoding="utf-8")):
            if lang not in LANGUAGES:
                continue
            if lang == "python":
                snippets.append(_classify(Snippet(page, start, "python", "\n".join(body))))
                continue
            for line, command in _command_lines(lang, start, body):
                words = shlex.split(command, comments=True)
                plain = not {"&&", "||", "|", ";"} & set(words)
                if plain and words[:1] == ["openpbr-diffuse"]:
                    kind = "cli"
                elif (
                    plain
                    and words[:1] == ["python"]
                    and re.fullmatch(r"tools/\w+\.py", words[1] if len(words) > 1 else "")
                ):
                    kind = "tool"
                else:
                    kind = "shell"
                snippets.append(_classify(Snippet(page, line, kind, command, _expected_status(command))))
        if snippets:
            out[page] = snippets
    return out


SNIPPETS = collect()
ALL = [s for snippets in SNIPPETS.values() for s in snippets]


@dataclass
class PageRun:
    """The scratch folder, Python namespace and results of one page's snippets."""

    folder: Path
    namespace: dict = field(default_factory=dict)
    results: dict = field(default_factory=dict)  # snippet id -> (status, output)

    def run(self, s: Snippet) -> tuple[int, str]:
        if s.id not in self.results:
            self.results[s.id] = self._python(s) if s.kind == "python" else self._cli(s)
        return self.results[s.id]

    def _python(self, s: Snippet) -> tuple[int, str]:
        cwd = os.getcwd()
        os.chdir(self.folder)
        try:
            exec(compile(s.text, s.id, "exec"), self.namespace)  # noqa: S102 - the page's own example
        except BaseException:  # noqa: BLE001 - any exception fails the block
            return 1, traceback.format_exc()
        finally:
            os.chdir(cwd)
        return 0, ""

    def _cli(self, s: Snippet) -> tuple[int, str]:
        env = dict(os.environ, NO_COLOR="1", COLUMNS="80", MPLBACKEND="Agg")
        env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        words = shlex.split(s.text, comments=True)
        if s.kind == "tool":
            argv = [sys.executable, str(ROOT / words[1]), *words[2:]]
        else:
            argv = [sys.executable, "-m", "openpbr_diffuse", *words[1:]]
        r = subprocess.run(
            argv,
            cwd=self.folder,
            env=env,
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
        )
        return r.returncode, (r.stdout[-2000:] + "\n--- stderr ---\n" + r.stderr[-3000:])


_RUNS: dict[str, PageRun] = {}


@pytest.fixture
def page_run(tmp_path_factory):
    def get(page: str) -> PageRun:
        if page not in _RUNS:
            folder = tmp_path_factory.mktemp(re.sub(r"\W", "_", page))
            (folder / "materials").symlink_to(ROOT / "materials", target_is_directory=True)
            (folder / "tests").mkdir()
            (folder / "tests" / "subjects").symlink_to(ROOT / "tests" / "subjects", target_is_directory=True)
            _RUNS[page] = PageRun(folder)
        return _RUNS[page]

    return get


def _param(s: Snippet):
    marks = [pytest.mark.slow] if s.slow else []
    return pytest.param(s, id=s.id, marks=marks)


@pytest.mark.parametrize("snippet", [_param(s) for s in ALL if not s.skip])
def test_documented_snippet_runs(snippet: Snippet, page_run):
    assert snippet.kind != "shell", (
        f"{snippet.id}: {snippet.text!r} is neither an openpbr-diffuse command nor in SKIP (with the reason)"
    )
    run = page_run(snippet.page)
    for earlier in SNIPPETS[snippet.page]:
        if earlier is snippet:
            break
        if earlier.writes and not earlier.skip:
            status, output = run.run(earlier)
            if status != earlier.expect:
                pytest.fail(f"an earlier snippet of the page, {earlier.id}, failed:\n{output}", pytrace=False)
    status, output = run.run(snippet)
    if status != snippet.expect:
        pytest.fail(f"{snippet.text}\n\nexit status {status}, expected {snippet.expect}\n{output}", pytrace=False)


@pytest.mark.parametrize("table", ["SKIP", "SLOW"])
def test_skip_and_slow_entries_name_documented_commands(table):
    """Every entry still matches a snippet of its page: the lists cannot go stale."""
    stale = [
        (page, needle)
        for page, needle, _ in globals()[table]
        if not any(s.page == page and needle in s.text for s in ALL)
    ]
    assert not stale, stale


def test_commands_not_run_here_are_listed_with_a_reason():
    """The documented commands this test does not run are those ``SKIP`` lists with a reason
    (installers and the test suite, run by ``.ci/run``; benchmarks; the Blender, npm and Dask
    set-ups), and nothing else is left out."""
    not_run = [s for s in ALL if s.skip]
    assert not_run, "SKIP matches no documented command"
    reasons = {r for _, _, r in SKIP}
    for s in not_run:
        assert s.skip in reasons, s.id


def test_snippets_are_found():
    """The reader finds the blocks (a change of fence style would otherwise run nothing)."""
    kinds = {s.kind for s in ALL}
    assert {"python", "cli", "shell"} <= kinds
    assert any(s.page == "README.md" and s.kind == "python" for s in ALL)
    assert sum(s.kind == "cli" and not s.skip and not s.slow for s in ALL) >= 5
    assert all(s.text.strip() for s in ALL)
