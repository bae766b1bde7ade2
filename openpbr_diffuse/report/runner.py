"""Run every report section and write the report atomically.

:func:`run_report` builds each section of :data:`.sections.SECTIONS` in order (a section
module that is not installed is listed as "not available"; a section that raises is listed
as "error" with a failing check), then writes ``index.html``, ``report.json`` and the
images into a temporary directory beside the output directory and moves it into place
only when everything was written: an existing report is replaced only by a complete one.

``report.json`` schema (``"schema": "openpbr-diffuse-report/2"``)::

    {"schema", "version" (library), "generated" (UTC ISO 8601), "quick" (bool),
     "paths" [str], "select" [str] (the --select patterns, [] = everything),
     "implementation": null | UNDER_TEST,      # the implementation under test (first screen)
     "evidence": {"passed", "n_checks", "n_failed", "n_not_run"},   # the library's own checks
     "passed" (bool: the library's evidence), "n_checks", "n_failed", "elapsed_s",
     "sections": [{"key", "title", "status": "pass"|"fail"|"error"|"not run"|"findings"|"not available",
                   "not_run" (str|null: why nothing ran), "elapsed_s", "error" (str|null),
                   "notes" [str], "warnings" [str], "checks": [CHECK],
                   "tables": [{"caption", "columns", "rows"}],
                   "lists": [{"title", "items" [str]}] (e.g. one per graded implementation),
                   "findings" (int|null: a findings section's count of failing quantities),
                   "figures": [{"file" ("images/<key>_*.png"), "caption"}]}],
     "checks": [CHECK],       # every check of every section, flattened
     "explorer": {"file" ("explore.html"), "subject" (str|null: the GLSL file shown beside the
                  reference), "function" (str|null), "message" (str: why its GLSL is not in the page)},
     "materials": [MATERIAL]} # every material of the materials section, in file order ([] without it)
    CHECK = {"id" ("section.check_slug", stable), "section", "name", "measured", "threshold",
             "comparison" ("<=", ">=", "=="), "expected" (null unless "=="), "unit",
             "reference" (provenance), "detail", "passed" (bool), "status": "pass"|"fail"|"not run",
             "not_run" (str|null: why)}
    UNDER_TEST = {"name", "kind" ("vectors"|"code"), "status" = "tier": "conforms"|
                  "conforms with warnings"|"does not conform"|"could not run", "headline",
                  "verdict_line" (the last line of the output), "error", "version" {str: str}, "notes" [str],
                  "figures": [{"file", "caption"}],
                  "verdicts": [{"id" ("implementation.brdf", ...), "quantity", "label", "status",
                                "diagnosis" (deviation name|null), "sentence", "max_abs_error",
                                "where" (the inputs of the largest error), "n", "n_failed",
                                "detail", "worst" [row]}]}

    MATERIAL = {"file" (absolute), "relpath" (relative to the given path it was found under),
                "index" (position in its file), "material" (prim / node path; null: the file
                could not be read), "name", "shader", "kind" (shader family), "node",
                "diffuse_model", "verdict": "fail"|"flagged"|"unsupported"|"pass",
                "reasons" [str], "detail", "base_color" [3], "roughness",
                "diffuse_weight" [3], "diffuse_probability", "albedo" [3] (at theta_o = 30 deg),
                "albedo_mu" {"1", "0.5", "0.2": [3]}, "albedo_max", "albedo_limit",
                "probability_error", "not_modelled" [str] (first 5), "n_not_modelled",
                "warnings" [str] (first 5), "n_warnings"}       # numbers null when not evaluated

Schema 1 had no "id"/"status"/"not_run" on checks, no "implementation", "evidence", "select"
and section statuses "pass"|"fail"|"error"|"not available" only (a section with 0 checks was
"pass"; it is now "not run" or "findings").

Non-finite numbers are written as null (JSON has no NaN).
"""

from __future__ import annotations

import datetime
import importlib
import json
import math
import os
import time
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from .. import _signals
from . import _plot, output
from .model import Check, Context, SectionResult, slug

if TYPE_CHECKING:
    from ..graders.subject import Subject
    from ..library import LibraryOptions
    from .explore import ExplorerSubject
    from .subject import UnderTest

SCHEMA = "openpbr-diffuse-report/2"
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
    under_test: UnderTest | None = None

    @property
    def checks(self) -> list:
        return [c for s in self.sections for c in s.result.checks]

    @property
    def passed(self) -> bool:
        """The library's own evidence: every check that ran passes and no section crashed."""
        return all(c.passed for c in self.checks if c.status != "not run") and not any(
            s.status == "error" for s in self.sections
        )

    @property
    def exit_status(self) -> int:
        """0 conforms and the evidence passes, 1 does not conform (or a check fails),
        3 the implementation could not run (:data:`.subject.EXIT_COULD_NOT_RUN`)."""
        if self.under_test is not None:
            from .subject import COULD_NOT_RUN, DOES_NOT_CONFORM, EXIT_COULD_NOT_RUN

            status = self.under_test.status
            if status == DOES_NOT_CONFORM:
                return 1
            if status == COULD_NOT_RUN:
                return EXIT_COULD_NOT_RUN
        return 0 if self.passed else 1


def default_paths() -> list[Path]:
    """The bundled ``materials/`` folder (read by openpbr_diffuse.readers), or [] when the
    installation does not carry it."""
    from ..readers import BUNDLED_MATERIALS

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
            raise ValueError(
                f"report: {p} is not a USD or MaterialX file "
                f"(expected one of {', '.join(MATERIAL_SUFFIXES)}, or a folder)"
            )
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


def matches(patterns: Iterable[str], text: str) -> bool:
    """Whether ``text`` (a check id or section key) matches one of the glob ``patterns``."""
    import fnmatch

    return any(fnmatch.fnmatchcase(text, p) for p in patterns)


def section_selected(key: str, patterns: Sequence[str] | None) -> bool:
    """A section runs when a pattern matches its key or the section part of a check id."""
    if not patterns:
        return True
    return any(matches([p], key) or matches([p.split(".", 1)[0]], key) for p in patterns)


def assign_ids(res: SectionResult) -> None:
    """Give every check of ``res`` its stable id ``section.check_slug`` (unique in the section)."""
    seen: dict = {}
    for c in res.checks:
        base = c.id or f"{res.key}.{slug(c.name)}"
        n = seen.get(base, 0)
        seen[base] = n + 1
        c.id = base if n == 0 else f"{base}_{n + 1}"


def _status(res: SectionResult) -> str:
    ran = [c for c in res.checks if c.status != "not run"]
    if not ran:
        if res.tables and not res.not_run:
            return "findings"
        res.not_run = res.not_run or (
            "; ".join(sorted({c.not_run for c in res.checks if c.not_run})) or "the section made no checks"
        )
        return "not run"
    return "pass" if all(c.passed for c in ran) else "fail"


def run_section(key: str, ctx: Context, select: Sequence[str] | None = None) -> SectionRun:
    """Build one section; never raises (errors become an "error" section).

    ``select``: glob patterns of check ids; checks matching none are dropped (a pattern
    matching the section key keeps them all).
    """
    from . import sections

    modname = f"{sections.__name__}.{key}"
    t0 = time.perf_counter()
    try:
        module = importlib.import_module(modname)
    except ModuleNotFoundError as exc:
        if exc.name == modname:
            res = SectionResult(key, _section_title(key), notes=["This section is not available in this installation."])
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
        table = getattr(module, "CHECKS", None)
        if table is not None:  # every check declared (KeyError otherwise), the quick run's not-run rows
            for c in res.checks:
                c.id = table.spec(c.id or c.name).id
            table.complete(res, ctx.quick)
    except Exception as exc:  # a broken section must not lose the rest of the report
        return _error(SectionResult(key, title), key, f"{type(exc).__name__}: {exc}", t0)
    assign_ids(res)
    if select and not matches(select, key):
        res.checks = [c for c in res.checks if matches(select, c.id)]
        if not res.checks:
            res.not_run = "no check of this section matches --select " + " ".join(select)
    return SectionRun(res, _status(res), time.perf_counter() - t0)


#: The implementation's verdicts and their sub-checks (``report --glsl/--cpp/--vectors/--implementation``).
IMPLEMENTATION_IDS = (
    ("implementation.brdf", "(with --glsl / --cpp / --vectors / --implementation)"),
    ("implementation.albedo", "(with --glsl / --cpp / --vectors / --implementation)"),
    ("implementation.properties", "(with --glsl / --cpp / --implementation: the properties of its own functions)"),
    ("implementation.sampler_pdf", "(with --glsl / --cpp / --vectors / --implementation)"),
    ("implementation.sampler_chi2", "(with --glsl / --cpp / --vectors / --implementation)"),
    ("implementation.sampler_pdf.normalisation", "(with --sample-function / --pdf-function)"),
    ("implementation.sampler_pdf.reference", "(with --sample-function / --pdf-function)"),
    ("implementation.sampler_chi2.chi2", "(with --sample-function / --pdf-function)"),
    ("implementation.sampler_chi2.valid", "(with --sample-function / --pdf-function)"),
    ("implementation.sampler_chi2.variance", "(with --sample-function / --pdf-function)"),
)


def declared_checks(
    keys: Sequence[str] | None = None, select: Sequence[str] | None = None, quick: bool = False
) -> list[tuple[str, str]]:
    """Every declared check id and its title, read from the sections' ``CHECKS`` tables (no
    section is built): ``[(id, title)]`` in page order, then the implementation's ids.

    A section with no declared check is listed as ``key.section`` ("findings"); with
    ``quick``, the checks ``--quick`` leaves out are marked "(not run in --quick)".

    Examples
    --------
    >>> ids = [i for i, _ in declared_checks(["albedo"])]
    >>> ids[0], "implementation.brdf" in ids
    ('albedo.lambert_directional_albedo_closed_form_vs_table', True)
    >>> declared_checks(["graders"])[0]
    ('graders.section', '(findings)')
    """
    from . import sections as section_pkg

    keys = tuple(section_pkg.SECTIONS if keys is None else keys)
    if select and not any(section_selected(k, select) for k in keys) and not matches(select, "implementation.x"):
        raise ValueError(
            f"--select: no section or check id matches {' '.join(select)} "
            f"(sections: {', '.join(section_pkg.SECTIONS)}; see --list-checks)"
        )
    out = []
    for key in keys:
        if not section_selected(key, select):
            continue
        try:
            module = importlib.import_module(f"{section_pkg.__name__}.{key}")
        except ModuleNotFoundError:
            out.append((f"{key}.section", "(not available)"))
            continue
        specs = module.CHECKS.specs
        if not specs:
            out.append((f"{key}.section", "(findings)"))
        for spec in specs:
            if select and not matches(select, key) and not matches(select, spec.id):
                continue
            out.append((spec.id, spec.title + (" (not run in --quick)" if quick and not spec.quick else "")))
    from ..conformance.properties import PROPERTY_IDS

    props = [(f"implementation.{p}", "(with --glsl / --cpp / --implementation)") for p in PROPERTY_IDS]
    return out + list(IMPLEMENTATION_IDS) + props


def _error(res, key, message, t0):
    res.checks.append(
        Check(
            name="section ran",
            measured=math.nan,
            threshold=0.0,
            comparison="==",
            expected=0.0,
            detail=message,
            reference="the section's build()",
            section=key,
        )
    )
    assign_ids(res)
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


def build_document(
    run: ReportRun,
    *,
    paths: Sequence[str | os.PathLike[str]],
    quick: bool,
    elapsed_s: float,
    select: Sequence[str] | None = (),
    figures: Sequence[tuple[str, str]] = (),
    materials: Sequence[dict] = (),
) -> dict:
    """``report.json``'s document (see the module docstring for the schema)."""
    from .._version import __version__

    sections = []
    for s in run.sections:
        r = s.result
        sections.append(
            {
                "key": r.key,
                "title": r.title,
                "status": s.status,
                "not_run": r.not_run,
                "elapsed_s": round(s.elapsed_s, 3),
                "error": s.error,
                "notes": list(r.notes),
                "warnings": list(r.warnings),
                "checks": [c.to_dict() for c in r.checks],
                "tables": [asdict(t) for t in r.tables],
                "lists": list(r.lists),
                "findings": r.findings,
                "figures": [{"file": f"{IMAGE_DIR}/{f.file}", "caption": f.caption} for f in r.figures],
            }
        )
    checks = [c.to_dict() for c in run.checks]
    n_failed = sum(c["status"] == "fail" for c in checks)
    n_not_run = sum(c["status"] == "not run" for c in checks)
    under = None
    if run.under_test is not None:
        under = run.under_test.to_dict()
        under["figures"] = [{"file": f"{IMAGE_DIR}/{f}", "caption": c} for f, c in figures]
    return _clean(
        {
            "schema": SCHEMA,
            "version": __version__,
            "generated": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "quick": bool(quick),
            "paths": [str(p) for p in paths],
            "select": list(select or ()),
            "implementation": under,
            "evidence": {
                "passed": run.passed,
                "n_checks": len(checks) - n_not_run,
                "n_failed": n_failed,
                "n_not_run": n_not_run,
            },
            "passed": run.passed,
            "n_checks": len(checks),
            "n_failed": n_failed,
            "elapsed_s": round(elapsed_s, 3),
            "sections": sections,
            "checks": checks,
            "materials": list(materials),
        }
    )


class _SectionLines:
    """Progress of the sections as lines on stderr (stderr is not a terminal)."""

    def __init__(self, total):
        self.total, self.n = total, 0

    def set_description(self, key):
        import sys

        print(f"report: section {self.n + 1}/{self.total} {key}", file=sys.stderr, flush=True)

    def set_postfix_str(self, text, refresh=True):
        pass

    def update(self, n):
        self.n += n

    def close(self):
        pass


def _progress_bar(total, enabled):
    """A tqdm bar on stderr (disabled when not wanted); lines when ``enabled == "lines"``."""
    if enabled == "lines":
        return _SectionLines(total)
    from tqdm.auto import tqdm

    return tqdm(
        total=total,
        unit="section",
        disable=not enabled or enabled == "none",
        dynamic_ncols=True,
        bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}] {postfix}",
    )


def run_report(
    paths: list | None = None,
    out: str | Path = "report",
    *,
    quick: bool = False,
    progress: bool | str = True,
    sections: Sequence[str] | None = None,
    select: Sequence[str] | None = None,
    under_test: UnderTest | None = None,
    subject: Subject | None = None,
    library: LibraryOptions | None = None,
    explorer: ExplorerSubject | None = None,
) -> ReportRun:
    """Run the report and write ``out/index.html``, ``out/report.json``, ``out/images/`` and
    ``out/explore.html`` (the lobe explorer, :mod:`.explore`).

    Parameters
    ----------
    paths : list of path-like, optional
        Material files or folders; default the bundled ``materials/``.
    out : path-like
        Output directory; replaced only when the new report is complete.
    quick : bool
        Smaller grids and sample counts (seconds instead of tens of seconds).
    progress : bool or {"bar", "lines", "none"}
        Show a progress bar on stderr (True: "bar"); "lines": a line per section and, while
        the materials are read, every few seconds (for a stderr that is not a terminal).
    sections : sequence of str, optional
        Section keys to run (default all of :data:`.sections.SECTIONS`, in that order).
    select : sequence of str, optional
        Glob patterns of check ids / section keys (``--select``): only those sections run and
        only the matching checks are kept.
    under_test : UnderTest, optional
        The implementation under test, already graded (:mod:`.subject`): shown first,
        counted apart from the library's evidence; ``subject`` (its callables), when given,
        is drawn in the pictures.
    library : LibraryOptions, optional
        How the materials section reads the files (:mod:`openpbr_diffuse.library`): worker
        processes, cache, Dask cluster, number of previews (default: in this process, no
        cache; its progress follows ``progress``).
    explorer : ExplorerSubject, optional
        A GLSL implementation under test (:func:`.explore.explorer_subject`): the explorer page
        shows its function beside the reference, with the difference.

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
        raise ValueError(
            f"sections: unknown section(s) {', '.join(unknown)}; expected some of {', '.join(section_pkg.SECTIONS)}"
        )
    select = [str(p) for p in (select or ())]
    keys = tuple(k for k in keys if section_selected(k, select))
    if select and not keys and not (under_test is not None and matches(select, "implementation.x")):
        raise ValueError(
            f"--select: no section or check id matches {' '.join(select)} "
            f"(sections: {', '.join(section_pkg.SECTIONS)}; see --list-checks)"
        )
    out = output.check_target(out, paths)  # before any work: never replace what this tool did not write
    tmp = None
    t0 = time.perf_counter()
    try:
        # made with the termination signals held: one that arrives meanwhile is delivered
        # once ``tmp`` names the folder, inside this ``try``, whose handler removes it
        with _signals.blocked():
            tmp = output.staging_dir(out)
        image_dir = tmp / IMAGE_DIR
        image_dir.mkdir()
        run = ReportRun(under_test=under_test)
        figures = _subject_figures(under_test, subject, image_dir, quick)
        bar = _progress_bar(len(keys), progress)
        try:
            ctx = Context(
                image_dir=image_dir,
                paths=list(paths),
                quick=quick,
                progress=lambda message: bar.set_postfix_str(str(message)[:60], refresh=True),
                extra={"library": _library_options(library, progress)},
            )
            with _plot.style():
                for key in keys:
                    bar.set_description(key)
                    run.sections.append(run_section(key, ctx, select))
                    bar.update(1)
        finally:
            bar.close()
        doc = build_document(
            run,
            paths=paths,
            quick=quick,
            elapsed_s=time.perf_counter() - t0,
            select=select,
            figures=figures,
            materials=ctx.extra.get("materials", ()),
        )
        from .explore import write_explorer_into

        doc["explorer"] = write_explorer_into(tmp, explorer)
        run.document = doc
        (tmp / "report.json").write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n")
        (tmp / "index.html").write_text(render_html(doc, image_dir), encoding="utf-8")
        output.publish(tmp, out, paths)
    except BaseException:
        if tmp is not None:
            output.discard(tmp)
        raise
    run.out_dir = out
    return run


def _library_options(library, progress):
    """The materials section's options; its progress follows the report's unless set."""
    from ..library import LibraryOptions

    mode = {True: "bar", False: "none"}.get(progress, progress) if isinstance(progress, bool) else progress
    if library is None:
        return LibraryOptions(progress=str(mode))
    return library


def _subject_figures(under_test, subject, image_dir, quick):
    """The pictures of the implementation under test ([] when it cannot be called)."""
    if under_test is None or subject is None or under_test.error:
        return []
    from .subject import figures

    try:
        return figures(subject, under_test, image_dir, quick=quick)
    except Exception as exc:  # noqa: BLE001 -- a picture must not lose the verdicts
        under_test.notes.append(f"pictures not drawn: {type(exc).__name__}: {' '.join(str(exc).split())}")
        return []


__all__ = [
    "run_report",
    "run_section",
    "matches",
    "section_selected",
    "assign_ids",
    "declared_checks",
    "ReportRun",
    "SectionRun",
    "SCHEMA",
    "default_paths",
]
