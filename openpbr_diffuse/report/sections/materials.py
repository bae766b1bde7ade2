"""Report section "materials": every material of the given files (or the bundled library).

The files are read one at a time (:mod:`openpbr_diffuse.library`: in worker processes, from
the cache, or on a Dask cluster, as ``ctx.extra["library"]`` says; serially and uncached
without it), each reduced to one compact record per material and dropped, so the cost grows
with the number of files, never with the square of it, and the heavy objects (stages, nodes,
figures) never pile up.  The records (``ctx.extra["materials"]``, ``report.json``'s
``"materials"``: every material, in file order) carry the node each maps onto, the diffuse
lobe's weight and selection probability and the directional albedo at theta_o = 30 deg, the
albedo at mu = 1, 0.5, 0.2, a verdict and its reasons.

The section summarises the library: counts by verdict, shader kind and reason, the worst
materials, fixed-size histograms of the diffuse roughness, the base colour and the albedo
(``materials_distributions.png``); a preview render (directional light | furnace) and an
albedo plot (total and the diffuse lobe's share) of at most ``previews`` materials, failing
and flagged first (``materials_<n>_<name>_render.png``, ``..._albedo.png``), each its own
small figure, with its resolved parameters and their provenance.  The page's table of every
material (filter, sort) is drawn from the records.

Checks, against properties the lobe stack must have, computed with each material's node:
every file is read; every material is evaluated; the directional albedo does not exceed 1
beyond the diffuse model's known overshoot (QON: up to 1.0152, EON-paper Fig. 5; EON /
Lambert: 2e-3, the GGX albedo-table accuracy); the lobe selection probabilities sum to 1.
Strings from the files are returned as plain text (the runner escapes them).
"""

from __future__ import annotations

import base64
import re
from typing import Any

import numpy as np

from ...library.worker import OVERSHOOT, PROBABILITY_TOLERANCE, THETA_O  # noqa: F401 -- part of this module's API
from ..model import CheckTable, Context, Figure, SectionResult, Table

TITLE = "Materials"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("materials")

KEY = "materials"
#: Rows of the worst-materials table; entries of a check's detail; warnings listed.
WORST_ROWS = 20
DETAIL_ITEMS = 20
WARNINGS_LISTED = 30


def _slug(k: int, name: str) -> str:
    """A file-name part for the ``k``-th drawn material."""
    return f"{k:02d}_" + re.sub(r"[^A-Za-z0-9]+", "_", name or "material").strip("_")[:40]


def _listing(items: list[str], limit: int = DETAIL_ITEMS) -> str:
    """At most ``limit`` items joined, with how many more."""
    more = len(items) - limit
    return "; ".join(items[:limit]) + (f"; ... and {more} more" if more > 0 else "")


def _fmt(v: Any) -> str:
    """A value of a record as table text."""
    if v is None:
        return "-"
    if isinstance(v, (tuple, list)):
        return "(" + ", ".join(f"{x:.4g}" if x is not None else "-" for x in v) + ")"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _file_record(f: Any, error: str) -> dict[str, Any]:
    """The record standing for a file that could not be read."""
    from ...library.summary import FILE_NOT_READ
    from ...library.worker import empty_record

    rec = empty_record()
    rec.update(kind="(file not read)", verdict="fail", reasons=[FILE_NOT_READ], detail=error)
    return {"file": f.path, "relpath": f.relpath, "index": 0, **rec}


def read_library(ctx: Context, opts: Any, runner: Any) -> tuple[list, list, list]:
    """(files, records, unreadable "relpath: error" texts) of ``ctx.paths`` (or the bundled library).

    >>> from pathlib import Path
    >>> from openpbr_diffuse.library import LibraryOptions
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> ctx = Context(Path("."), paths=[BUNDLED_MATERIALS / "clay_rough.mtlx"], quick=True)
    >>> opts = LibraryOptions()
    >>> with opts.runner() as runner:
    ...     files, records, unreadable = read_library(ctx, opts, runner)
    >>> [(r["relpath"], r["material"], r["verdict"]) for r in records], unreadable
    ([('clay_rough.mtlx', 'clay_rough', 'pass')], [])
    """
    from ...library import Progress, Task, list_files
    from ...readers import BUNDLED_MATERIALS

    files = list_files(ctx.paths or [BUNDLED_MATERIALS])
    task = Task(kind="report", n_mu=16 if ctx.quick else 46)
    records: list[dict[str, Any]] = []
    unreadable: list[str] = []
    with Progress(len(files), opts.progress, "materials", position=1) as progress:
        for o in runner.run([(f.path, task) for f in files], progress):
            f = files[o.index]
            if o.payload.get("error"):
                unreadable.append(f"{f.relpath}: {o.payload['error']}")
                records.append(_file_record(f, o.payload["error"]))
                continue
            for k, rec in enumerate(o.payload["records"]):
                records.append({"file": f.path, "relpath": f.relpath, "index": k, **rec})
    return files, records, unreadable


def _checks(res: SectionResult, files: list, records: list, unreadable: list) -> None:
    """The section's checks: every file read, every material evaluated, albedo and probabilities."""
    from ...library.summary import FILE_NOT_READ, excess

    mats = [r for r in records if FILE_NOT_READ not in r["reasons"]]
    failed = [r for r in mats if "not evaluated" in r["reasons"]]
    evaluated = [r for r in mats if r.get("albedo_max") is not None or r.get("probability_error") is not None]
    # an input that cannot be read, or a material that cannot be evaluated, is a failed check
    res.checks.append(
        CHECKS.check(
            "every given material file is read",
            float(len(unreadable)),
            0.0,
            "<=",
            unit="unreadable files",
            reference=f"{len(files)} files",
            detail=_listing(unreadable),
        )
    )
    res.checks.append(
        CHECKS.check(
            "every material found is evaluated",
            float(len(failed)),
            0.0,
            "<=",
            unit="materials not evaluated",
            reference=f"{len(mats)} materials",
            detail=_listing([f"{r['material']}: {r['detail']}" for r in failed]),
        )
    )
    why = "no material of the given files was evaluated" if not evaluated else None
    over = sorted((r for r in evaluated if r.get("albedo_max") is None or excess(r) > 0), key=lambda r: -excess(r))
    worst = max((excess(r) for r in evaluated), default=float("nan"))
    res.checks.append(
        CHECKS.check(
            "every material's directional albedo <= 1 (within its diffuse model's allowance)",
            float("inf") if any(r.get("albedo_max") is None for r in evaluated) else worst,
            0.0,
            "<=",
            unit="largest albedo above the allowance",
            reference="energy conservation; allowance 0.0172 for QON (its known overshoot, EON paper Fig. 5, "
            "and the GGX table accuracy), 2e-3 for EON and Lambert (the GGX albedo-table accuracy); "
            f"theta_o in [0, 87] deg, {len(evaluated)} materials",
            detail=_listing([f"{r['relpath']} {r['material']}: {r['detail']}" for r in over]),
            not_run=why,
        )
    )
    perr = [r["probability_error"] for r in evaluated if r.get("probability_error") is not None]
    bad = [r for r in evaluated if r.get("probability_error") is None or r["probability_error"] > PROBABILITY_TOLERANCE]
    res.checks.append(
        CHECKS.check(
            "every material's lobe selection probabilities sum to 1",
            float("inf") if len(perr) < len(evaluated) else max(perr, default=float("nan")),
            PROBABILITY_TOLERANCE,
            "<=",
            unit="largest |sum - 1|",
            reference=f"OpenPBR spec, reduction to a mixture of lobes; {len(evaluated)} materials",
            detail=_listing([f"{r['relpath']} {r['material']}: {r['probability_error']}" for r in bad]),
            not_run=why,
        )
    )


def _tables(res: SectionResult, records: list) -> None:
    """The summary tables: by verdict, by shader kind, by reason, the worst materials."""
    from ...library.summary import by_kind, by_reason, by_verdict, worst_key

    res.tables.append(Table("Materials by verdict", ["verdict", "materials"], by_verdict(records)))
    res.tables.append(
        Table(
            "Materials by shader kind",
            ["shader kind", "materials", "fail", "flagged", "unsupported", "pass"],
            by_kind(records),
        )
    )
    reasons = by_reason(records)
    if reasons:
        res.tables.append(Table("Materials by reason", ["reason", "materials"], reasons))
    worst = sorted(records, key=worst_key)[:WORST_ROWS]
    res.tables.append(
        Table(
            f"The worst {len(worst)} materials: failing first, then flagged, then by the largest albedo "
            "against its allowance",
            ["verdict", "file", "material", "shader kind", "largest albedo / allowance", "reasons", "detail"],
            [
                [
                    r["verdict"],
                    r["relpath"],
                    r["material"] or "-",
                    r["kind"],
                    f"{_fmt(r.get('albedo_max'))} / {_fmt(r.get('albedo_limit'))}",
                    ", ".join(r["reasons"]) or "-",
                    r["detail"] or "-",
                ]
                for r in worst
            ],
        )
    )


def _distributions(records: list, path: Any) -> bool:
    """Histograms (fixed bins) of the diffuse roughness, base colour and albedo at three mu."""
    from ...library.summary import distributions
    from ...library.worker import MUS
    from .._plot import pyplot

    d = distributions(records)
    if not len(d["roughness"]) and not len(d["base_color"]):
        return False
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(10.5, 2.8), dpi=80)
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.2, top=0.95, wspace=0.25)
    bins = np.linspace(0.0, 1.0, 21)
    axes[0].hist(np.clip(d["roughness"], 0.0, 1.0), bins=bins, color="0.4")
    axes[0].set_xlabel("diffuse roughness")
    for c, colour in enumerate(("tab:red", "tab:green", "tab:blue")):
        if len(d["base_color"]):
            axes[1].hist(np.clip(d["base_color"][:, c], 0.0, 1.0), bins=bins, histtype="step", color=colour)
    axes[1].set_xlabel("base colour R, G, B (ACEScg, clipped to [0, 1])")
    for mu, ls in zip(MUS, ("-", "--", ":")):
        a = d[f"albedo_mu={mu:g}"]
        if len(a):
            axes[2].hist(
                np.clip(a, 0.0, 1.05), bins=np.linspace(0.0, 1.05, 22), histtype="step", ls=ls, label=f"mu {mu:g}"
            )
    axes[2].set_xlabel("directional albedo (mean of R, G, B)")
    axes[2].legend(fontsize=7)
    for ax in axes:
        ax.set_ylabel("materials", fontsize=8)
        ax.tick_params(labelsize=7)
    fig.savefig(path)
    plt.close(fig)
    return True


def _figures(ctx: Context, res: SectionResult, runner: Any, records: list, cap: int) -> int:
    """Previews, albedo plots and parameter tables of the chosen materials; how many were drawn."""
    from ...library import Task
    from ...library.summary import chosen_for_figures

    chosen = chosen_for_figures(records, cap)
    by_file: dict[str, list[int]] = {}
    for k in chosen:
        by_file.setdefault(records[k]["file"], []).append(k)
    n_mu, size = (16, 32) if ctx.quick else (46, 72)
    files = list(by_file)
    items = [
        (f, Task(kind="detail", n_mu=n_mu, size=size, select=tuple(sorted(records[k]["index"] for k in by_file[f]))))
        for f in files
    ]
    drawn: dict[int, dict[str, Any]] = {}
    for o in runner.run(items):
        at = {records[k]["index"]: k for k in by_file[files[o.index]]}
        for d in o.payload.get("records", []):
            if d.get("index") in at:
                drawn[at[d["index"]]] = d
    n = 0
    for rank, k in enumerate(chosen):
        d, r = drawn.get(k), records[k]
        if d is None or d.get("error"):
            res.warnings.append(f"{r['relpath']} {r['material']}: not drawn: {(d or {}).get('error', 'not found')}")
            continue
        slug = _slug(rank, r["name"])
        render = f"materials_{slug}_render.png"
        (ctx.image_dir / render).write_bytes(base64.b64decode(d["preview_png"]))
        plot = f"materials_{slug}_albedo.png"
        (ctx.image_dir / plot).write_bytes(base64.b64decode(d["albedo_png"]))
        where = f"{r['relpath']} {r['material']} ({r['verdict']})"
        res.figures.append(Figure(render, f"{where}: directional light (left), uniform white furnace (right)"))
        res.figures.append(
            Figure(
                plot,
                f"{where}: directional albedo against theta_o (solid, R G B), diffuse lobe's weight x albedo (dashed)",
            )
        )
        res.tables.append(
            Table(
                f"{rank:02d} {r['material']} ({r['shader']}): resolved parameters",
                ["parameter", "value", "kind", "provenance"],
                d["parameters"],
            )
        )
        n += 1
    return n


def _notes(
    ctx: Context, opts: Any, runner: Any, read: tuple[int, int], files: list, records: list, drawn: int
) -> list[str]:
    """What was read and how (``read``: files computed, from the cache), and what the previews show."""
    computed, cached = read
    n_mats = sum(r["material"] is not None for r in records)
    how = (
        f"on the Dask cluster {opts.scheduler or ''}".rstrip()
        if runner.remote
        else f"{opts.jobs} worker processes"
        if opts.jobs > 1
        else "in one process"
    )
    cache = f", {cached} from the cache ({opts.cache.folder})" if opts.cache is not None else " (no cache)"
    return [
        f"{n_mats} materials from {len(files)} files"
        + (" (the bundled library)" if not ctx.paths else "")
        + ". Colours in ACEScg (the readers' working space); evaluated at uv (0.5, 0.5), default time and "
        f"variants. Diffuse weight, probability and albedo at theta_o = {THETA_O:g} deg; the weight includes "
        "base_weight, (1 - metalness) and the albedo scaling 1 - E_specular(mu_o).",
        f"Previews and albedo plots: {drawn} of {n_mats} materials (at most {opts.previews}: failing first, then "
        "flagged, then in file order). Every material is in the table below and in report.json (\"materials\").",
        f"Files: {computed} read {how}{cache}.",
    ]


def _warnings(opts: Any, records: list, unreadable: list) -> list[str]:
    """The files and materials that could not be read or evaluated (at most ``WARNINGS_LISTED``), cache and reader warnings."""
    warnings = [f"cannot be read: {text}" for text in unreadable[:WARNINGS_LISTED]]
    bad = [r for r in records if "not evaluated" in r["reasons"]]
    for r in bad[: max(0, WARNINGS_LISTED - len(unreadable))]:
        warnings.append(f"{r['relpath']} {r['material']}: not evaluated: {r['detail']}")
    more = len(unreadable) + len(bad) - WARNINGS_LISTED
    if more > 0:
        warnings.append(f"... and {more} more files or materials that could not be read (see the table)")
    if opts.cache is not None and opts.cache.write_error:
        warnings.append(f"the cache could not be written (the results were not kept): {opts.cache.write_error}")
    n_warned = sum(bool(r.get("n_warnings")) for r in records)
    if n_warned:
        warnings.append(f"{n_warned} materials carry reader warnings (listed per material in the table)")
    return warnings


def build(ctx: Context) -> SectionResult:
    """Read every material file, check the records, summarise them and draw the chosen materials."""
    from ...library import LibraryOptions

    res = SectionResult(KEY, TITLE)
    opts = ctx.extra.get("library") or LibraryOptions()
    with opts.runner() as runner:
        ctx.progress("materials: reading")
        files, records, unreadable = read_library(ctx, opts, runner)
        read = runner.computed, runner.cached  # the reading's counts, before the figures' work
        ctx.extra["materials"] = records
        _checks(res, files, records, unreadable)
        _tables(res, records)
        ctx.progress("materials: pictures")
        if _distributions(records, ctx.image_dir / "materials_distributions.png"):
            res.figures.append(
                Figure(
                    "materials_distributions.png",
                    "Distributions over the evaluated materials: diffuse roughness, base colour (R G B) and the "
                    "directional albedo at mu = 1, 0.5, 0.2",
                )
            )
        drawn = _figures(ctx, res, runner, records, opts.previews)
    res.notes += _notes(ctx, opts, runner, read, files, records, drawn)
    res.warnings += _warnings(opts, records, unreadable)
    return res


__all__ = ["TITLE", "build", "read_library"]
