"""The tiers of ``check``: conforms / conforms with warnings / does not conform, over checks
with stable ids, an expected-failure list for CI, and JUnit XML.

A check is ``{"id", "status", "detail"}`` with status ``pass``, ``warn`` (a named, bounded
deviation: passes with a note), ``fail``, ``skip`` or, after :func:`apply_expected`,
``expected failure`` (a listed check that fails: does not fail the run) and
``unexpectedly passes`` (a listed check that passes: reported, with what to do).

Exit status of ``check``: 0 conforms (also with warnings), 1 does not conform
(:data:`EXIT`); 2 is unusable input, decided before any grading.
"""

from __future__ import annotations

from pathlib import Path

from ..result import Result
from .grade import CONFORMS, CONFORMS_WITH_WARNINGS, DOES_NOT_CONFORM, Grade

#: exit status per tier
EXIT = {CONFORMS: 0, CONFORMS_WITH_WARNINGS: 0, DOES_NOT_CONFORM: 1}
EXPECTED_FAILURE = "expected failure"
UNEXPECTED_PASS = "unexpectedly passes"
#: an --expect-fail file larger than this is not a list of ids
MAX_EXPECT_BYTES = 1 << 20


def check_from_grade(check_id: str, g: Grade | dict) -> dict:
    """A values grade as one check (a :class:`~openpbr_diffuse.result.Result` as JSON): pass /
    warn (its tier is "conforms with warnings") / fail, with the largest error in tolerances as
    ``measured``, the named deviation as ``finding`` and the worst rows.

    >>> c = check_from_grade("values.eon", {"tier": "conforms", "passed": True, "diagnosis_detail": "ok"})
    >>> c["status"], c["tier"], c["detail"]
    ('pass', 'conforms', 'ok')
    """
    d = g if isinstance(g, dict) else g.to_dict()
    tier = d.get("tier") or (CONFORMS if d["passed"] else DOES_NOT_CONFORM)
    status = {CONFORMS: "pass", CONFORMS_WITH_WARNINGS: "warn"}.get(tier, "fail")
    detail = d.get("diagnosis_detail") or ""
    if status == "warn":
        detail = "; ".join(d.get("warnings") or []) or detail
    elif status == "fail" and d.get("diagnosis"):
        detail = f"{d['diagnosis']} -- {detail}"
    return Result(
        id=check_id,
        quantity=check_id,
        measured=d.get("max_normalised_error"),
        threshold=1.0,
        unit="x tolerance",
        outcome=status,
        tier=tier,
        diagnosis=None if status == "pass" else d.get("diagnosis"),
        worst=list(d.get("worst") or [])[:3],
        detail=detail,
    ).to_dict()


def tier_of(checks: list[dict]) -> str:
    """The tier of a list of checks: any ``fail`` does not conform; else any ``warn`` or
    ``unexpectedly passes`` conforms with warnings; else conforms.

    >>> tier_of([{"id": "a", "status": "pass"}, {"id": "b", "status": "warn"}])
    'conforms with warnings'
    >>> tier_of([{"id": "a", "status": "expected failure"}])
    'conforms'
    """
    statuses = {c["status"] for c in checks}
    if "fail" in statuses:
        return DOES_NOT_CONFORM
    if statuses & {"warn", UNEXPECTED_PASS}:
        return CONFORMS_WITH_WARNINGS
    return CONFORMS


def read_expect_fail(path: str | Path) -> list[str]:
    """The check ids of an expected-failure file: one per line, ``#`` starts a comment.

    Raises ValueError naming ``--expect-fail`` and the file when it cannot be read as text.

    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "xfail.txt"
    >>> _ = p.write_text("# known\\nproperty.reciprocity  # f_ms\\n\\nvalues.eon\\n")
    >>> read_expect_fail(p)
    ['property.reciprocity', 'values.eon']
    """
    p = Path(path)
    try:
        if p.stat().st_size > MAX_EXPECT_BYTES:
            raise ValueError(f"--expect-fail {path}: larger than {MAX_EXPECT_BYTES} bytes, not a list of check ids")
        text = p.read_bytes().decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else "not UTF-8 text"
        raise ValueError(f"--expect-fail {path}: cannot be read ({why})") from None
    ids = []
    for n, line in enumerate(text.splitlines(), 1):
        item = line.split("#", 1)[0].strip()
        if not item:
            continue
        if any(ch.isspace() for ch in item):
            raise ValueError(f"--expect-fail {path}: line {n}: one check id per line, got {item!r}")
        ids.append(item)
    return ids


def apply_expected(checks: list[dict], expected: list[str], path: str = "FILE") -> tuple[list[dict], list[str]]:
    """Mark the listed checks: a failing one becomes ``expected failure``, a passing one
    ``unexpectedly passes`` (with "remove it from FILE"); ids that match no check are noted.

    >>> cs = [{"id": "a", "status": "fail", "detail": "x"}, {"id": "b", "status": "pass", "detail": "y"}]
    >>> out, notes = apply_expected(cs, ["a", "b", "c"], "xfail.txt")
    >>> [c["status"] for c in out], out[1]["detail"]
    (['expected failure', 'unexpectedly passes'], 'unexpectedly passes: remove it from xfail.txt (y)')
    >>> notes
    ['xfail.txt lists c, which is not a check of this run']
    """
    listed = set(expected)
    out = []
    for c in checks:
        c = dict(c)
        if c["id"] in listed:
            if c["status"] == "fail":
                c["status"] = c["verdict"] = EXPECTED_FAILURE
                c["detail"] = f"expected failure (listed in {path}): {c['detail']}"
            elif c["status"] in ("pass", "warn"):
                c["status"] = c["verdict"] = UNEXPECTED_PASS
                c["detail"] = f"unexpectedly passes: remove it from {path} ({c['detail']})"
        out.append(c)
    ids = {c["id"] for c in checks}
    notes = [f"{path} lists {i}, which is not a check of this run" for i in expected if i not in ids]
    return out, notes


def print_checks(checks: list[dict], indent: str = "  ") -> None:
    """One line per check that is not a plain pass (the passes counted)."""
    passed = sum(c["status"] == "pass" for c in checks)
    print(f"{indent}checks: {passed} of {len(checks)} pass")
    for c in checks:
        if c["status"] != "pass":
            print(f"{indent}  [{c['status']}] {c['id']}: {c['detail']}")


def junit_xml(name: str, checks: list[dict], tier: str) -> str:
    """JUnit XML of the checks: one testcase per check
    (:func:`openpbr_diffuse.result.junit_case`): ``fail`` is a ``<failure>``, ``skip`` a
    ``<skipped>``; a ``warn``, ``expected failure`` or ``unexpectedly passes`` is a passed
    testcase with a ``<properties>`` entry (``status``) and the note in ``<system-out>``.

    >>> x = junit_xml("mine.csv", [{"id": "values.eon", "status": "warn", "detail": "eq14"}], "conforms with warnings")
    >>> '<property name="status" value="warn" />' in x, "<failure" in x
    (True, False)
    """
    from xml.etree import ElementTree as ET

    from ..result import junit_case

    root = ET.Element("testsuites", name="openpbr-diffuse check", tests=str(len(checks)))
    root.set("failures", str(sum(c["status"] == "fail" for c in checks)))
    suite = ET.SubElement(root, "testsuite", name=name, tests=str(len(checks)), failures=root.get("failures", "0"))
    suite.set("skipped", str(sum(c["status"] == "skip" for c in checks)))
    ET.SubElement(ET.SubElement(suite, "properties"), "property", name="tier", value=tier)
    for c in checks:
        junit_case(suite, c, c["id"].rpartition(".")[0] or "check")
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


__all__ = [
    "EXIT",
    "EXPECTED_FAILURE",
    "UNEXPECTED_PASS",
    "apply_expected",
    "check_from_grade",
    "junit_xml",
    "print_checks",
    "read_expect_fail",
    "tier_of",
]
