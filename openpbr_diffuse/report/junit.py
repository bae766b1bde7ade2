"""``report --junit FILE``: the report's checks as JUnit XML for CI dashboards.

One ``<testsuite>`` per section (and one, ``implementation``, for the implementation under
test), one ``<testcase>`` per check, named by its stable id: a failing check carries
``<failure message=...>`` with what was measured against what; a check that did not run
(and a section that ran nothing) is ``<skipped message=...>`` with the reason.  An
implementation that could not run is an ``<error>``.  The materials the report read have
a suite of their own, ``materials.library``: one ``<testcase>`` per material.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from xml.etree import ElementTree as ET

from .._outfile import output_file
from ..result import junit_case


def _case(suite: ET.Element, classname: str, name: str, elapsed: float = 0.0) -> ET.Element:
    return ET.SubElement(suite, "testcase", classname=classname, name=name, time=f"{elapsed:.3f}")


def junit_xml(doc: dict) -> str:
    """The JUnit XML text of a report document (``report.json``): every result -- a check, an
    implementation's verdict, a verdict's sub-check -- is one ``<testcase>`` made by
    :func:`openpbr_diffuse.result.junit_case`.

    Examples
    --------
    >>> doc = {"sections": [{"key": "s", "title": "S", "status": "pass", "elapsed_s": 0.1, "not_run": None,
    ...        "checks": [{"id": "s.a", "name": "a", "status": "fail", "measured": 2, "comparison": "<=",
    ...                    "threshold": 1, "detail": "", "not_run": None}]}], "implementation": None}
    >>> "<failure" in junit_xml(doc)
    True
    """
    root = ET.Element("testsuites", name="openpbr-diffuse report")
    ut = doc.get("implementation")
    if ut:
        suite = ET.SubElement(root, "testsuite", name="implementation")
        props = ET.SubElement(suite, "properties")
        ET.SubElement(props, "property", name="tier", value=str(ut.get("status", "")))
        ET.SubElement(props, "property", name="verdict", value=str(ut.get("verdict_line", "")))
        for v in ut.get("verdicts", []):
            junit_case(suite, v, "implementation")
            for c in v.get("checks") or ():  # sub-checks (the sampler's), by their stable ids
                junit_case(suite, c, "implementation")
        if ut.get("error") or not ut.get("verdicts"):
            case = _case(suite, "implementation", "implementation.run")
            ET.SubElement(case, "error", message=f"could not run: {ut.get('error') or 'nothing to grade'}")
    for s in doc.get("sections", []):
        suite = ET.SubElement(root, "testsuite", name=s["key"])
        if not s.get("checks"):
            case = _case(suite, s["key"], f"{s['key']}.section", s.get("elapsed_s") or 0.0)
            why = s.get("not_run") or s.get("status", "")
            if s.get("status") == "error":
                ET.SubElement(case, "error", message=str(s.get("error")))
            elif s.get("status") != "pass":
                ET.SubElement(case, "skipped", message=f"{s.get('status')}: {why}")
            continue
        for c in s["checks"]:
            junit_case(suite, c, s["key"])
    _material_cases(root, doc.get("materials") or ())
    for suite in root:
        cases = suite.findall("testcase")
        suite.set("tests", str(len(cases)))
        suite.set("failures", str(sum(c.find("failure") is not None for c in cases)))
        suite.set("errors", str(sum(c.find("error") is not None for c in cases)))
        suite.set("skipped", str(sum(c.find("skipped") is not None for c in cases)))
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def _material_cases(root: ET.Element, materials: Iterable[dict]) -> None:
    """One ``<testcase>`` per material of the report (suite ``materials.library``), named
    ``relpath:material``: a failing material carries ``<failure>`` with its reasons, an
    unsupported one is ``<skipped>``, a flagged one passes with its reasons as output."""
    suite = None
    for r in materials:
        if suite is None:
            suite = ET.SubElement(root, "testsuite", name="materials.library")
        reasons = ", ".join(r.get("reasons") or ()) or r.get("verdict", "")
        case = _case(suite, "materials.library", f"{r.get('relpath')}:{r.get('material') or '(file)'}")
        if r.get("verdict") == "fail":
            ET.SubElement(case, "failure", message=f"{reasons}: {r.get('detail') or ''}"[:1000]).text = r.get("file")
        elif r.get("verdict") == "unsupported":
            ET.SubElement(case, "skipped", message=f"{reasons}: {r.get('detail') or ''}"[:1000])
        elif r.get("verdict") == "flagged":
            ET.SubElement(case, "system-out").text = f"{reasons}: {r.get('detail') or ''}"


def write_junit(
    doc: dict,
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    inputs: Iterable[str | os.PathLike[str]] = (),
    input_suffixes: Iterable[str] = (),
) -> Path:
    """Write :func:`junit_xml` of ``doc`` to ``path`` by the rule of every output file.

    An existing file is replaced only with ``force`` (a regular file, never a link or one
    of ``inputs``); the XML goes to a temporary sibling first, see
    :func:`openpbr_diffuse._outfile.output_file`.  Raises ``OutputFileError`` (a
    ``ValueError``) naming ``--junit`` and the path.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> doc = {"sections": [], "implementation": None}
    >>> write_junit(doc, d / "junit.xml").read_text().startswith("<?xml")
    True
    >>> write_junit(doc, d / "junit.xml")
    Traceback (most recent call last):
    ...
    openpbr_diffuse._outfile.OutputExistsError: --junit .../junit.xml exists: not overwritten (use --force to replace it)
    """
    with output_file(path, option="--junit", force=force, inputs=inputs, input_suffixes=input_suffixes) as tmp:
        tmp.write_text(junit_xml(doc), encoding="utf-8")
    return Path(os.path.abspath(os.fspath(path)))


__all__ = ["junit_xml", "write_junit"]
