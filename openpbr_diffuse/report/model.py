"""The data a report section produces: checks, tables, figures and notes.

A section module (``openpbr_diffuse.report.sections.<key>``) defines ``TITLE`` (str) and
``build(ctx: Context) -> SectionResult``.  It computes its numbers with the library, writes
its images into ``ctx.image_dir`` (file names prefixed with the section key) and returns
plain data; the runner turns that into ``report.json`` and ``index.html`` (escaping every
string), so a section never writes HTML itself.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..result import Result


def Check(  # noqa: N802 -- the constructor of a report check, kept under its name
    name: str,
    measured: Any,
    threshold: Any,
    comparison: str = "<=",
    reference: str = "",
    expected: float | None = None,
    unit: str = "",
    detail: str = "",
    section: str = "",
    not_run: str | None = None,
    id: str = "",
) -> Result:
    """One check of the report: a :class:`~openpbr_diffuse.result.Result` whose ``measured``
    is compared with ``threshold``.

    ``comparison`` says how: ``"<="`` (measured must not exceed threshold, e.g. an error),
    ``">="`` (e.g. a variance ratio), or ``"=="`` with the tolerance in ``threshold``
    against ``expected``.  ``reference`` is the provenance of what was compared against
    (e.g. "Gauss-Legendre quadrature of evaluate, order 16", "data/albedo_eon.csv",
    "paper Table 1"); ``not_run``: why the check did not run (no GL driver, no compiler, bpy
    absent) -- it then neither passes nor fails and is shown as "not run".

    >>> c = Check("white furnace |E - 1|", 2e-4, 1e-3, reference="quadrature")
    >>> c.status, c.passed, c.to_dict()["tier"]
    ('pass', True, 'conforms')
    """
    return Result(
        id=id,
        quantity=name,
        measured=measured,
        threshold=threshold,
        comparison=comparison,
        reference=reference,
        expected=expected,
        unit=unit,
        detail=detail,
        section=section,
        not_run=not_run,
    )


#: Why a check that ``report --quick`` leaves out did not run (its compile or run time is the
#: larger part of a quick report's; the full report runs it).
QUICK_NOT_RUN = "not run in --quick: run `openpbr-diffuse report` for it"


#: The lobe models ``report --quick`` checks: the conformance vectors' models (EON, its Eq. 14
#: form, FON, QON, Lambert: the lobes OpenPBR and MaterialX define).  The full report checks
#: every model of the registry; the quick one lists the other models' checks as not run.  Each
#: model's verbs are batch drivers of their own to compile, so a first quick run compiles half.
QUICK_MODELS = ("lambert", "qon", "fon", "eon", "eon_approx")

#: The sampling strategies ``report --quick`` checks: those of the OpenPBR surface's diffuse
#: lobe (EON's CLTC + uniform mixture, and cosine sampling for the other diffuse models).
QUICK_STRATEGIES = ("cosine", "eon")


#: rho of a grey or white surface as an RGB triple.  The report calls the lobe models with
#: three channels everywhere (its colours are RGB): a model's driver is compiled for one
#: channel count, and a scalar rho beside an RGB one would compile every model twice.
WHITE = (1.0, 1.0, 1.0)


def grey(v: float) -> tuple:
    """rho = v in each of the three RGB channels (see ``WHITE``).

    >>> grey(0.8)
    (0.8, 0.8, 0.8)
    """
    return (v, v, v)


def skipped_in_quick(name: str, reference: str = "", detail: str = "", unit: str = "") -> Result:
    """A check that ``report --quick`` does not run: listed as "not run", never passed.

    >>> c = skipped_in_quick("live simulation vs the closed form")
    >>> c.status, c.passed, c.not_run == QUICK_NOT_RUN
    ('not run', False, True)
    """
    return Check(name, math.nan, math.nan, reference=reference, detail=detail, unit=unit, not_run=QUICK_NOT_RUN)


def slug(text: str) -> str:
    """A check name as an id part: lower case, runs of other characters as one ``_``.

    >>> slug("eon: white furnace |E - 1| at rho = 1")
    'eon_white_furnace_e_1_at_rho_1'
    """
    import re

    return re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_")[:60] or "check"


@dataclass
class Table:
    """A table shown in the page and stored in the JSON (cells: str, int or float)."""

    caption: str
    columns: list[str]
    rows: list[list[Any]]


@dataclass
class Figure:
    """An image written by the section into ``ctx.image_dir`` (``file`` is its name there)."""

    file: str
    caption: str


@dataclass
class SectionResult:
    """What a section returns; ``notes`` are plain-text paragraphs (escaped when shown)."""

    key: str
    title: str
    checks: list[Result] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    #: why the section ran nothing (shown as "not run"), when it did not
    not_run: str | None = None
    #: titled lists (e.g. one per graded implementation): [{"title": str, "items": [str]}]
    lists: list[dict] = field(default_factory=list)
    #: a findings section's count of findings (a third party's failing quantities), else None
    findings: int | None = None

    def __post_init__(self):
        for c in self.checks:
            c.section = c.section or self.key


@dataclass
class Context:
    """What a section gets: where to put images, the material files, and the run mode.

    ``paths``: the material files (USD / MaterialX) the user gave, or the bundled
    ``materials/``; ``quick``: smaller grids for a fast run; ``progress(message)``: call
    it between long steps (the runner shows a progress bar).
    """

    image_dir: Path
    paths: list[Path] = field(default_factory=list)
    quick: bool = False
    progress: Callable[[str], None] = lambda message: None
    extra: dict[str, Any] = field(default_factory=dict)


def in_quick(ctx: Context, names: tuple, quick_names: tuple) -> tuple:
    """The names a section runs: all of ``names``, or (``ctx.quick``) those in ``quick_names``.

    >>> in_quick(Context(Path("."), quick=True), ("eon", "full_on"), QUICK_MODELS)
    ('eon',)
    """
    return tuple(n for n in names if not ctx.quick or n in quick_names)


@dataclass(frozen=True)
class CheckSpec:
    """One declared check of a section: its stable ``id``, its ``title`` (the name shown) and
    whether ``report --quick`` runs it (``quick=False``: listed as "not run" in a quick run).

    ``reference`` and ``unit`` are shown on the not-run row.
    """

    id: str
    title: str
    quick: bool = True
    reference: str = ""
    unit: str = ""


#: The static registry of the report's checks: one tab-separated row per check (id, quick
#: yes/no, reference, unit, title), in page order.  Ids are stable (``--select`` and
#: ``--expect-fail`` lists name them); a section's ``CHECKS`` is its rows.
REGISTRY = Path(__file__).resolve().parent.parent / "data" / "report_checks.tsv"


@functools.cache
def registry() -> tuple[CheckSpec, ...]:
    """Every declared check of the report, read from :data:`REGISTRY` (comment lines skipped).

    >>> specs = registry()
    >>> specs[0].id, len({s.id for s in specs}) == len(specs)
    ('models.lambert_reciprocity_f_wi_wo_f_wo_wi', True)
    """
    specs = []
    for n, line in enumerate(REGISTRY.read_text(encoding="utf-8").splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        parts = line.split("\t")
        if len(parts) != 5 or parts[1] not in ("yes", "no"):
            raise ValueError(f"{REGISTRY.name} line {n}: expected id, yes/no, reference, unit, title separated by tabs")
        cid, quick, reference, unit, title = parts
        specs.append(CheckSpec(cid, title, quick == "yes", reference, unit))
    return tuple(specs)


class CheckTable:
    """A section's checks in page order (``CHECKS = CheckTable.declared(key)``: its rows of
    the static :func:`registry`).

    ``build`` makes its checks with :meth:`check` (by title or id: an undeclared one raises
    KeyError); the runner gives every declared check that ``report --quick`` leaves out a
    "not run" row (:meth:`not_run_in_quick`) and puts the checks in declared order;
    ``report --list-checks`` reads these tables without building any section.

    Examples
    --------
    >>> t = CheckTable("demo", [("demo.a", "a holds"), ("demo.b", "b holds", False)])
    >>> t.ids
    ('demo.a', 'demo.b')
    >>> c = t.check("a holds", 0.5, 1.0)
    >>> c.id, c.passed
    ('demo.a', True)
    >>> [(c.id, c.status) for c in t.not_run_in_quick()]
    [('demo.b', 'not run')]
    """

    def __init__(self, section: str, specs: list | tuple) -> None:
        self.section = section
        self.specs = tuple(s if isinstance(s, CheckSpec) else CheckSpec(*s) for s in specs)
        self._by_id = {s.id: s for s in self.specs}
        self._by_title = {s.title: s for s in self.specs}
        bad = [s.id for s in self.specs if not s.id.startswith(section + ".")]
        if bad or len(self._by_id) != len(self.specs):
            raise ValueError(f"CheckTable {section!r}: ids must be unique and start with {section + '.'!r}: {bad}")

    @classmethod
    def declared(cls, section: str) -> CheckTable:
        """The table of ``section``: its rows of the static registry :data:`REGISTRY`, in order.

        >>> t = CheckTable.declared("albedo")
        >>> t.ids[0], t.spec(t.ids[0]).quick
        ('albedo.lambert_directional_albedo_closed_form_vs_table', True)
        >>> CheckTable.declared("graders").ids  # a findings section declares none
        ()
        """
        return cls(section, [s for s in registry() if s.id.split(".", 1)[0] == section])

    @property
    def ids(self) -> tuple:
        return tuple(s.id for s in self.specs)

    def spec(self, key: str) -> CheckSpec:
        """The declared check of id or title ``key`` (KeyError when undeclared)."""
        s = self._by_id.get(key) or self._by_title.get(key)
        if s is None:
            raise KeyError(f"check {key!r} is not declared in {self.section}.CHECKS")
        return s

    def check(
        self, key: str, measured: float, threshold: float, comparison: str = "<=", reference: str = "", **kw: Any
    ) -> Result:
        """A report check (:func:`Check`) of the declared check ``key`` (its title as name, its id)."""
        s = self.spec(key)
        return Check(s.title, measured, threshold, comparison, reference, id=s.id, section=self.section, **kw)

    def not_run_in_quick(self) -> list[Result]:
        """The checks ``report --quick`` leaves out, as "not run"."""
        return [
            Check(
                s.title,
                math.nan,
                math.nan,
                reference=s.reference or "the full report (`openpbr-diffuse report`)",
                unit=s.unit,
                not_run=QUICK_NOT_RUN,
                id=s.id,
                section=self.section,
            )
            for s in self.specs
            if not s.quick
        ]

    def complete(self, res: SectionResult, quick: bool) -> None:
        """Add the quick run's not-run rows ``res`` lacks and sort its checks in declared order
        (checks outside the table, e.g. an error's, go last)."""
        have = {c.id for c in res.checks}
        if quick:
            res.checks += [c for c in self.not_run_in_quick() if c.id not in have]
        order = {i: k for k, i in enumerate(self.ids)}
        res.checks.sort(key=lambda c: order.get(c.id, len(order)))
