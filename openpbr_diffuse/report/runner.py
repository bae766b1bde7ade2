"""Run every report section and write the report atomically.

:func:`run_report` builds each section of :data:`.sections.SECTIONS` in order (a section
module that is not installed is listed as "not available"; a section that raises is listed
as "error" with a failing check), then writes ``index.html``, ``report.json`` and the
images into a temporary directory beside the output directory and moves it into place
only when everything was written: an existing report is replaced only by a complete one.

``report.json`` schema (``"schema": "openpbr-diffuse-report/1"``)::

    {"schema", "version" (library), "generated" (UTC ISO 8601), "quick" (bool),
     "paths" [str], "passed" (bool), "n_checks", "n_failed", "elapsed_s",
     "sections": [{"key", "title", "status": "pass"|"fail"|"error"|"not available",
                   "elapsed_s", "error" (str|null), "notes" [str], "warnings" [str],
                   "checks": [CHECK], "tables": [{"caption", "columns", "rows"}],
                   "figures": [{"file" ("images/<key>_*.png"), "caption"}]}],
     "checks": [CHECK]}       # every check of every section, flattened
    CHECK = {"section", "name", "measured", "threshold", "comparison" ("<=", ">=", "=="),
             "expected" (null unless "=="), "unit", "reference" (provenance), "detail",
             "passed" (bool)}

Non-finite numbers are written as null (JSON has no NaN).
"""
from __future__ import annotations

import datetime
import importlib
import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from . import output
from .model import Check, Context, SectionResult

SCHEMA = "openpbr-diffuse-report/1"
IMAGE_DIR = "images"


@dataclass
class SectionRun:
    """A section's result plus how the run went."""

    result: SectionResult
    status: str
    elapsed_s: float = 0.0
    error: str | None = None


@dataclass
class ReportRun:
    """What :func:`run_report` returns: the sections, the status and where it was written."""

    sections: list = field(default_factory=list)
    out_dir: Path | None = None
    document: dict = field(default_factory=dict)

    @property
    def checks(self):
        return [c for s in self.sections for c in s.result.checks]

    @property
    def passed(self):
        return all(c.passed for c in self.checks) and not any(s.status == "error" for s in self.sections)

    @property
    def exit_status(self):
        return 0 if self.passed else 1


def default_paths():
    """The bundled ``materials/`` folder (issue 10's readers), or [] when not available."""
    try:
        from ..readers import BUNDLED_MATERIALS
    except ImportError:
        return []
    return [Path(BUNDLED_MATERIALS)] if Path(BUNDLED_MATERIALS).exists() else []


#: File types the report reads (USD, MaterialX); folders are searched by the materials section.
MATERIAL_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz", ".mtlx")


def _check_paths(paths):
    out = []
    for p in paths:
        p = Path(p)
        if not p.exists():
            raise FileNotFoundError(f"report: no such file or directory: {p}")
        if p.is_file() and p.suffix.lower() not in MATERIAL_SUFFIXES:
            raise ValueError(f"report: {p} is not a USD or MaterialX file "
                             f"(expected one of {', '.join(MATERIAL_SUFFIXES)}, or a folder)")
        if p.is_file():
            try:
                with open(p, "rb") as fh:
                    fh.read(1)
            except OSError as exc:
                raise OSError(f"report: cannot read {p}: {exc.strerror}") from None
        out.append(p)
    return out


def _section_title(key):
    return key.replace("_", " ").capitalize()


def run_section(key, ctx):
    """Build one section; never raises (errors become an "error" section)."""
    from . import sections

    modname = f"{sections.__name__}.{key}"
    t0 = time.perf_counter()
    try:
        module = importlib.import_module(modname)
    except ModuleNotFoundError as exc:
        if exc.name == modname:
            res = SectionResult(key, _section_title(key),
                                notes=["This section is not available in this installation."])
            return SectionRun(res, "not available")
        res = SectionResult(key, _section_title(key))
        return _error(res, key, f"import failed: {exc}", t0)
    title = getattr(module, "TITLE", _section_title(key))
    try:
        res = module.build(ctx)
        if not isinstance(res, SectionResult):
            raise TypeError(f"build() returned {type(res).__name__}, not SectionResult")
        res.key, res.title = key, res.title or title
        for c in res.checks:
            c.section = key
    except Exception as exc:  # a broken section must not lose the rest of the report
        return _error(SectionResult(key, title), key, f"{type(exc).__name__}: {exc}", t0)
    status = "pass" if all(c.passed for c in res.checks) else "fail"
    return SectionRun(res, status, time.perf_counter() - t0)


def _error(res, key, message, t0):
    res.checks.append(Check(name="section ran", measured=math.nan, threshold=0.0, comparison="==",
                            expected=0.0, detail=message, reference="the section's build()", section=key))
    return SectionRun(res, "error", time.perf_counter() - t0, message)


def _clean(x):
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if hasattr(x, "item") and callable(x.item):  # numpy scalars
        return _clean(x.item())
    if isinstance(x, Path):
        return str(x)
    return x


def build_document(run: ReportRun, *, paths, quick, elapsed_s):
    from .._version import __version__

    sections = []
    for s in run.sections:
        r = s.result
        sections.append({
            "key": r.key, "title": r.title, "status": s.status, "elapsed_s": round(s.elapsed_s, 3),
            "error": s.error, "notes": list(r.notes), "warnings": list(r.warnings),
            "checks": [c.to_dict() for c in r.checks],
            "tables": [asdict(t) for t in r.tables],
            "figures": [{"file": f"{IMAGE_DIR}/{f.file}", "caption": f.caption} for f in r.figures]})
    checks = [c.to_dict() for c in run.checks]
    return _clean({
        "schema": SCHEMA, "version": __version__,
        "generated": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "quick": bool(quick), "paths": [str(p) for p in paths], "passed": run.passed,
        "n_checks": len(checks), "n_failed": sum(not c["passed"] for c in checks),
        "elapsed_s": round(elapsed_s, 3), "sections": sections, "checks": checks})


def _progress_bar(total, enabled):
    """A tqdm bar on stderr (disabled when not wanted)."""
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="section", disable=not enabled, dynamic_ncols=True,
                bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}] {postfix}")


def run_report(paths=None, out="report", *, quick=False, progress=True, sections=None) -> ReportRun:
    """Run the report and write ``out/index.html``, ``out/report.json`` and ``out/images/``.

    Parameters
    ----------
    paths : list of path-like, optional
        Material files or folders; default the bundled ``materials/``.
    out : path-like
        Output directory; replaced only when the new report is complete.
    quick : bool
        Smaller grids and sample counts (seconds instead of tens of seconds).
    progress : bool
        Show a progress bar on stderr.
    sections : sequence of str, optional
        Section keys to run (default all of :data:`.sections.SECTIONS`, in that order).

    Raises
    ------
    FileNotFoundError, OSError
        A path does not exist or cannot be read (nothing is written).
    """
    from . import sections as section_pkg
    from .render import render_html

    paths = default_paths() if not paths else _check_paths(paths)
    keys = tuple(section_pkg.SECTIONS if sections is None else sections)
    unknown = [k for k in keys if k not in section_pkg.SECTIONS]
    if unknown:
        raise ValueError(f"sections: unknown section(s) {', '.join(unknown)}; "
                         f"expected some of {', '.join(section_pkg.SECTIONS)}")
    out = output.check_target(out, paths)
    tmp = output.staging_dir(out)
    t0 = time.perf_counter()
    try:
        image_dir = tmp / IMAGE_DIR
        image_dir.mkdir()
        run = ReportRun()
        bar = _progress_bar(len(keys), progress)
        try:
            ctx = Context(image_dir=image_dir, paths=list(paths), quick=quick,
                          progress=lambda message: bar.set_postfix_str(str(message)[:60], refresh=True))
            for key in keys:
                bar.set_description(key)
                run.sections.append(run_section(key, ctx))
                bar.update(1)
        finally:
            bar.close()
        doc = build_document(run, paths=paths, quick=quick, elapsed_s=time.perf_counter() - t0)
        run.document = doc
        (tmp / "report.json").write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n")
        (tmp / "index.html").write_text(render_html(doc, image_dir), encoding="utf-8")
        output.publish(tmp, out, paths)
    except BaseException:
        output.discard(tmp)
        raise
    run.out_dir = out
    return run


__all__ = ["run_report", "run_section", "ReportRun", "SectionRun", "SCHEMA", "default_paths"]
