"""One result type: a measured value against its threshold, with its verdict and finding.

Every grade the project makes is a :class:`Result`: the report's checks of the reference
(``report/sections``), an implementation's graded quantities (``graders.grading``: BRDF,
albedo, properties, the sampler's pdf and chi-square) and their sub-checks, the verdicts on
the report's first screen, a grade of submitted values (``conformance.grade.Grade`` is a
Result with the diagnosis's details) -- and the same record is what ``report.json``,
``check --json`` and JUnit carry (:meth:`Result.to_dict`).

The fields every result has:

- ``id``: the stable id (``albedo.eon_average_albedo_closed_form_vs_table``,
  ``implementation.brdf``, ``implementation.sampler_chi2.chi2``);
- ``quantity``: what was measured, in words (a check's title; ``brdf``, ``sampler pdf``);
- ``measured`` against ``threshold`` by ``comparison`` (``<=``, ``>=`` or ``==`` with
  ``expected``);
- ``verdict``: ``pass``, ``fail``, ``warn`` or ``not run`` (derived from the comparison unless
  the grader states it);
- ``tier``: ``conforms``, ``conforms with warnings``, ``does not conform`` or ``could not run``;
- ``finding``: the named deviation that explains a failure (None: none, or nothing failed),
  with ``sentence`` saying it in one sentence;
- ``worst``: the inputs of the worst cases (rows with ``wi``, ``wo``, ``mu``, ``roughness``,
  ``rho``, ``expected``, ``got``) and ``where``, the worst one in words.

``kind`` says the result's role: ``"check"`` (a check or sub-check: its ``status`` is its
verdict) or ``"quantity"`` (an implementation's graded quantity: its ``status`` is its tier).

Examples
--------
>>> r = Result(id="demo.error", quantity="an error", measured=0.5, threshold=1.0)
>>> r.verdict, r.effective_tier, r.passed
('pass', 'conforms', True)
>>> Result(quantity="x", measured=float("nan"), threshold=1.0).verdict
'fail'
>>> q = Result(id="implementation.brdf", quantity="brdf", kind="quantity", tier=DOES_NOT_CONFORM,
...            diagnosis="white_tint")
>>> q.status, q.verdict, q.finding
('does not conform', 'fail', 'white_tint')
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from operator import attrgetter
from typing import Any
from xml.etree import ElementTree as ET

#: The tiers of a verdict.
CONFORMS, CONFORMS_WITH_WARNINGS, DOES_NOT_CONFORM = "conforms", "conforms with warnings", "does not conform"
COULD_NOT_RUN = "could not run"
#: A check's verdicts.
PASS, FAIL, WARN, NOT_RUN, INFO, SKIP = "pass", "fail", "warn", "not run", "info", "skip"
_TIER_OF = {
    PASS: CONFORMS,
    WARN: CONFORMS_WITH_WARNINGS,
    FAIL: DOES_NOT_CONFORM,
    NOT_RUN: COULD_NOT_RUN,
    SKIP: COULD_NOT_RUN,
    INFO: CONFORMS,
    # after an expected-failure list (``conformance.tiers.apply_expected``)
    "expected failure": CONFORMS,
    "unexpectedly passes": CONFORMS_WITH_WARNINGS,
}
_VERDICT_OF = {CONFORMS: PASS, CONFORMS_WITH_WARNINGS: WARN, DOES_NOT_CONFORM: FAIL, COULD_NOT_RUN: NOT_RUN}
#: What a result is: a check (``status`` = verdict) or an implementation's quantity (``status`` = tier).
KINDS = ("check", "quantity")


#: An error ratio that a finite result makes too large for a float (|out - ref| / tolerance
#: above 1.8e308, e.g. out = 1e308) is recorded as this, the largest float; infinity is
#: kept for NaN and Inf results, so that the two are told apart.
OUT_OF_RANGE = sys.float_info.max


def json_safe(x: Any) -> Any:
    """``x`` with NumPy scalars as Python numbers and non-finite floats as JSON can hold them:
    NaN -> null, +-inf -> "inf" / "-inf" (the convention of ``check --json``).

    >>> import numpy as np
    >>> json_safe({"a": [np.float64(float("nan")), float("inf")], "b": np.int64(3)})
    {'a': [None, 'inf'], 'b': 3}
    """
    if hasattr(x, "item") and hasattr(x, "dtype") and getattr(x, "shape", None) == ():
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    return x


@dataclass
class Result:
    """One measured value against its threshold (see the module docstring for the fields)."""

    id: str = ""
    quantity: str = ""
    measured: Any = None
    threshold: Any = None
    comparison: str = "<="
    expected: float | None = None
    #: the grader's own verdict ("pass", "fail", "warn"); "" derives it from the comparison
    outcome: str = ""
    tier: str = ""
    #: the named deviation (the ``finding``)
    diagnosis: str | None = None
    sentence: str | None = None
    worst: list = field(default_factory=list)
    where: str = ""
    kind: str = "check"
    reference: str = ""
    unit: str = ""
    detail: str = ""
    section: str = ""
    #: why it did not run (no GL driver, no compiler, ``--quick``): neither passed nor failed
    not_run: str | None = None
    max_abs_error: Any = None
    rms_error: Any = None
    tolerance: Any = ""
    tolerance_reason: str = ""
    n: int = 0
    n_failed: int = 0
    excluded: int = 0
    #: sub-results (the sampler's normalisation, reference pdf, chi-square, validity, variance)
    checks: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    #: breakdown by region or case
    regions: Any = None
    #: the values' grade as JSON (``Grade.to_dict()``) when the quantity is a set of values
    grade: dict | None = None
    #: data for the pictures; not serialised
    plot: Any = field(default=None, repr=False, compare=False)
    #: the values' :class:`~openpbr_diffuse.conformance.grade.Grade`; not serialised
    values: Any = field(default=None, repr=False, compare=False)

    #: Derived from the fields above, read-only (the properties below the class); declared as
    #: fields (not set by ``__init__``) so that ``dataclasses.asdict`` carries them too.
    verdict: str = field(init=False, repr=False, compare=False)
    passed: bool = field(init=False, repr=False, compare=False)
    status: str = field(init=False, repr=False, compare=False)
    finding: str | None = field(init=False, repr=False, compare=False)
    name: str = field(init=False, repr=False, compare=False)

    @property
    def effective_tier(self) -> str:
        """The tier: the one given, else the verdict's ("pass" -> "conforms", ...)."""
        return self.tier or _TIER_OF[self.verdict]

    def to_dict(self) -> dict[str, Any]:
        """The result as JSON: the fields every result has (:data:`COMMON_KEYS`), then its
        role's own (:data:`CHECK_KEYS` for a check, :data:`QUANTITY_KEYS` for a quantity)."""
        own = CHECK_KEYS if self.kind == "check" else QUANTITY_KEYS
        d = {key: getattr(self, _ATTRIBUTE.get(key, key)) for key in (*COMMON_KEYS, *own)}
        if self.kind != "check":
            d["sentence"] = self.sentence or ""
            d["checks"] = [c.to_dict() if isinstance(c, Result) else c for c in self.checks]
        return json_safe(d)


def _verdict(r: Result) -> str:
    """ "pass", "fail", "warn" or "not run": the grader's own when it gave one, else the tier's
    (a quantity), else ``measured`` compared with ``threshold`` (NaN or None never passes)."""
    if r.not_run:
        return NOT_RUN
    if r.outcome:
        return r.outcome
    if r.kind == "quantity" and r.tier:
        return _VERDICT_OF[r.tier]
    return PASS if _compare(r.measured, r.threshold, r.comparison, r.expected) else FAIL


def _passed(r: Result) -> bool:
    """A quantity with a tier passes when it conforms outright (a warning tier is not a pass);
    anything else when its verdict is "pass", "warn" or "info" (measured, not graded)."""
    if r.kind == "quantity" and r.tier and not r.outcome and not r.not_run:
        return r.tier == CONFORMS
    return _verdict(r) in (PASS, WARN, INFO)


def _status(r: Result) -> str:
    """A check's verdict, or a quantity's tier."""
    return r.effective_tier if r.kind == "quantity" else _verdict(r)


Result.verdict = property(_verdict, doc=_verdict.__doc__)  # type: ignore[assignment]
Result.passed = property(_passed, doc=_passed.__doc__)  # type: ignore[assignment]
Result.status = property(_status, doc=_status.__doc__)  # type: ignore[assignment]
Result.finding = property(attrgetter("diagnosis"), doc="The named deviation that explains the failure, or None.")  # type: ignore[assignment]
Result.name = property(attrgetter("quantity"), doc="The quantity's name (a check's title).")  # type: ignore[assignment]


#: The JSON keys of every result, then those of a check and of a quantity (:meth:`Result.to_dict`).
COMMON_KEYS: tuple[str, ...] = ("id", "kind", "quantity", "measured", "threshold", "verdict", "status", "passed")
COMMON_KEYS += ("tier", "finding", "worst", "detail")
CHECK_KEYS = ("name", "comparison", "expected", "unit", "reference", "section", "not_run")
QUANTITY_KEYS: tuple[str, ...] = (
    "diagnosis",
    "sentence",
    "where",
    "max_abs_error",
    "rms_error",
    "tolerance",
    "tolerance_reason",
)
QUANTITY_KEYS += ("n", "n_failed", "excluded", "checks", "warnings", "regions", "grade")
#: JSON keys read from another attribute
_ATTRIBUTE = {"tier": "effective_tier"}


def _compare(measured: Any, threshold: Any, comparison: str, expected: float | None) -> bool:
    if measured is None or (isinstance(measured, float) and math.isnan(measured)):
        return False
    if comparison == "<=":
        return bool(measured <= threshold)
    if comparison == ">=":
        return bool(measured >= threshold)
    if comparison == "==":
        return bool(abs(measured - expected) <= threshold)  # type: ignore[operator]  # '==' results give expected
    raise ValueError(f"comparison must be '<=', '>=' or '==', got {comparison!r}")


def sub_check(id: str, verdict: str, measured: Any = None, threshold: Any = None, detail: str = "") -> Result:
    """A sub-result of a graded quantity (the sampler's) with the grader's own verdict.

    >>> sub_check("normalisation", "fail", 0.9, 5e-3, "pdf integrates to 0.9").to_dict()["status"]
    'fail'
    """
    if verdict not in (PASS, FAIL, WARN, NOT_RUN, INFO, SKIP):
        raise ValueError(f"verdict must be pass, fail, warn, info, skip or not run, got {verdict!r}")
    return Result(id=id, quantity=id, measured=measured, threshold=threshold, outcome=verdict, detail=detail)


def junit_case(suite: ET.Element, d: dict, classname: str, elapsed: float = 0.0) -> ET.Element:
    """One JUnit ``<testcase>`` for a result (``Result.to_dict()``, or a dict with at least
    ``id`` and ``status``), named by its id: ``fail`` and "does not conform" carry a
    ``<failure>`` (what was measured against what, or the finding); "not run" and ``skip`` a
    ``<skipped>``; "could not run" an ``<error>``; any other status that is not a plain pass
    (``warn``, "conforms with warnings", ``info``, "expected failure", "unexpectedly passes")
    passes with a ``status`` property and its note in ``<system-out>``.

    >>> suite = ET.Element("testsuite")
    >>> case = junit_case(suite, Result(id="a.b", quantity="b", measured=2.0, threshold=1.0).to_dict(), "a")
    >>> case.find("failure").get("message")
    'b: measured 2.0 <= 1.0'
    >>> junit_case(suite, {"id": "v", "status": "warn", "detail": "eq14"}, "check").find("system-out").text
    'eq14'
    """
    case = ET.SubElement(suite, "testcase", classname=classname, name=str(d["id"]), time=f"{elapsed:.3f}")
    status = d.get("status") or (PASS if d.get("passed") else FAIL)
    note = str(d.get("sentence") or d.get("detail") or "")
    if status in (FAIL, DOES_NOT_CONFORM):
        if d.get("comparison") and d.get("measured") is not None:
            message = (
                f"{d.get('name') or d.get('quantity')}: measured {d['measured']} {d['comparison']} {d['threshold']}"
            )
            message += f" (expected {d['expected']})" if d.get("expected") is not None else ""
            message += f" -- {d['finding']}" if d.get("finding") else ""
            text = str(d.get("detail") or "")
        elif status == DOES_NOT_CONFORM:
            message, text = f"does not conform: {note}", str(d.get("where") or "")
        else:
            message, text = note, note
        ET.SubElement(case, "failure", message=message[:1000]).text = text
    elif status in (NOT_RUN, SKIP):
        ET.SubElement(case, "skipped", message=f"{status}: {d.get('not_run') or note}"[:1000])
    elif status == COULD_NOT_RUN:
        ET.SubElement(case, "error", message=f"could not run: {note}"[:1000])
    elif status not in (PASS, CONFORMS):
        props = ET.SubElement(case, "properties")
        ET.SubElement(props, "property", name="status", value=str(status))
        ET.SubElement(case, "system-out").text = note
    return case


__all__ = [
    "COULD_NOT_RUN",
    "CONFORMS",
    "CONFORMS_WITH_WARNINGS",
    "DOES_NOT_CONFORM",
    "FAIL",
    "INFO",
    "OUT_OF_RANGE",
    "NOT_RUN",
    "PASS",
    "SKIP",
    "WARN",
    "Result",
    "json_safe",
    "junit_case",
    "sub_check",
]
