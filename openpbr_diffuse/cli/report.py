"""``openpbr-diffuse report``: does your implementation conform? (HTML + JSON + images).

    openpbr-diffuse report --glsl mine.glsl --function f [--albedo-function g]
    openpbr-diffuse report --cpp mine.cpp --function f --include DIR --define N=V
    openpbr-diffuse report --vectors filled.csv
    openpbr-diffuse report --implementation materialx-glsl
    openpbr-diffuse report                      # the reference's own evidence only
    openpbr-diffuse report --list-checks        # the stable check ids
    openpbr-diffuse report --select 'albedo.*' --junit junit.xml
    openpbr-diffuse report LIBRARY_DIR --quick --select materials   # a material library: parallel, cached

The implementation under test is graded first and its verdict is the first line of the page
and of the output; the library's own evidence follows, counted separately.  Writes
DIR/index.html (opens offline), DIR/report.json and DIR/images/, replacing an existing report
only when the new one is complete.  Exit status: 0 the implementation conforms (and the
library's evidence passes), 1 it does not conform (or a check of the evidence fails),
2 unusable input, 3 the implementation could not run (no GL driver, no compiler, ...).
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..graders.subject import Subject

#: Sections run as the library's evidence when an implementation is graded (``--evidence fast``).
FAST_EVIDENCE = ("implementations", "approximations")


#: The command's line in ``openpbr-diffuse --help``.
HELP = "does your implementation conform? HTML + JSON + images"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``report`` sub-command."""
    from ._library import add_library_options
    from ._options import add_command

    p = add_command(subparsers, "report", HELP, run, doc=__doc__)
    p.add_argument(
        "paths", nargs="*", metavar="PATHS", help="USD / MaterialX files or folders (default: the bundled materials/)"
    )
    p.add_argument("--out", default="report", metavar="DIR", help="output directory (default: report)")
    p.add_argument(
        "--quick",
        action="store_true",
        help="smaller grids and sample counts; the live simulations, the lobe models outside the "
        "conformance vectors' five and the samplers other than cosine and EON are listed as not run "
        "(the full report runs them)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar (nor progress lines)")
    add_library_options(p, previews=True)
    g = p.add_argument_group("the implementation under test")
    g.add_argument("--vectors", metavar="FILE", help="a filled vectors file (CSV / JSON with out_r, out_g, out_b)")
    _grader_arguments(g)
    g.add_argument("--model", default=None, metavar="MODEL", help="the model it claims (default eon)")
    c = p.add_argument_group("checks")
    c.add_argument(
        "--evidence",
        choices=("all", "fast", "none"),
        default=None,
        help="the library's own evidence to run: all sections, the fast ones "
        f"({', '.join(FAST_EVIDENCE)}; default with an implementation) or none",
    )
    c.add_argument(
        "--select",
        nargs="+",
        metavar="ID",
        default=None,
        help="run only these checks / sections (ids or glob patterns, e.g. 'albedo.*' models)",
    )
    c.add_argument(
        "--list-checks",
        action="store_true",
        help="print the declared check ids and titles (no section is run) and exit",
    )
    c.add_argument("--junit", metavar="FILE", help="also write the checks as JUnit XML")
    c.add_argument("--force", action="store_true", help="replace the --junit FILE if it exists (a regular file)")
    return p


def _grader_arguments(group: argparse._ArgumentGroup) -> None:
    """The graders' own options (``--glsl``, ``--cpp``, ``--implementation``...), less the report's own."""
    from ..graders import cli as gcli

    tmp = argparse.ArgumentParser(add_help=False)
    gcli.add_arguments(tmp)
    for action in tmp._actions:
        if action.dest in ("help", "quick", "json", "model"):
            continue
        kwargs = {"dest": action.dest, "default": action.default, "help": action.help}
        if action.metavar is not None:
            kwargs["metavar"] = action.metavar
        if action.choices is not None:
            kwargs["choices"] = action.choices
        if action.type is not None:
            kwargs["type"] = action.type
        if action.nargs is not None and not isinstance(action, argparse._StoreTrueAction):
            kwargs["nargs"] = action.nargs
        if isinstance(action, argparse._AppendAction):
            kwargs["action"] = "append"
        elif isinstance(action, argparse._StoreTrueAction):
            kwargs["action"] = "store_true"
            kwargs.pop("metavar", None)
        group.add_argument(*action.option_strings, **kwargs)


def subject_from_args(args: argparse.Namespace) -> Subject | None:
    """The Subject the options name, or None (``graders.cli.subject_from_args`` on the report's options)."""
    from ..graders import cli as gcli

    ns = argparse.Namespace(**{**vars(args), "quick": True, "json": False, "file": None, "model": args.model})
    return gcli.subject_from_args(ns)


def _under_test(args):
    """(UnderTest or None, Subject or None)."""
    from ..report.subject import (
        COULD_NOT_RUN,
        UnderTest,
        Verdict,
        grade_subject_under_test,
        grade_vectors_file,
    )

    code = [m for m in ("implementation", "glsl", "cpp", "wgsl") if getattr(args, m, None)]
    if args.vectors and code:
        raise ValueError("report: give one of --vectors, --glsl, --cpp, --wgsl, --implementation")
    if args.vectors:
        return grade_vectors_file(args.vectors), None
    if not code:
        for opt in ("function", "albedo_function", "sample_function", "pdf_function"):
            if getattr(args, opt, None):
                raise ValueError(f"report: --{opt.replace('_', '-')} needs --glsl, --cpp or --wgsl")
        return None, None
    from ..graders.errors import GraderUnavailable

    label = args.implementation or args.glsl or args.cpp or args.wgsl
    from pathlib import Path

    for opt in ("glsl", "cpp", "wgsl"):
        if getattr(args, opt, None) and not Path(getattr(args, opt)).is_file():
            raise FileNotFoundError(f"report: --{opt} {getattr(args, opt)}: no such file")
    try:
        subject = subject_from_args(args)
    except GraderUnavailable as exc:  # no GL driver / compiler / the code does not compile
        ut = UnderTest(name=str(label), kind="code", error=" ".join(str(exc).split()))
        ut.verdicts = [Verdict(q, COULD_NOT_RUN, detail=ut.error) for q in ("brdf",)]
        return ut, None
    return grade_subject_under_test(subject, quick=True, sampler_model=getattr(args, "sampler_model", None)), subject


def _explorer(args):
    """The GLSL function the report's explorer shows beside the reference (``--glsl`` with ``--function``)."""
    if not (getattr(args, "glsl", None) and getattr(args, "function", None)):
        return None
    from ..report.explore import explorer_subject

    return explorer_subject(args.glsl, args.function, args.include, args.define)


def _sections(args, under):
    from ..report.sections import SECTIONS

    evidence = args.evidence or ("fast" if under is not None and not args.select else "all")
    if evidence == "none":
        return ()
    return FAST_EVIDENCE if evidence == "fast" else SECTIONS


def _check_junit(args: argparse.Namespace) -> dict:
    """Check ``--junit FILE`` before any work (the output-file rule; never inside ``--out``);
    the keyword arguments of ``write_junit``: the run's inputs."""
    from pathlib import Path

    from .._outfile import OutputFileError, check_output_file
    from ..report.runner import MATERIAL_SUFFIXES, default_paths

    if not args.junit:
        if args.force:
            raise ValueError("--force applies to --junit FILE only (--out DIR has rules of its own)")
        return {}
    inputs = [*(args.paths or default_paths()), *(f for f in (args.vectors, args.glsl, args.cpp) if f)]
    kwargs = {"inputs": inputs, "input_suffixes": MATERIAL_SUFFIXES}
    target = check_output_file(args.junit, option="--junit", force=args.force, **kwargs)
    out = Path(args.out).resolve()
    if target.parent.resolve() == out or out in target.parent.resolve().parents:
        raise OutputFileError(
            f"--junit {args.junit} is inside the report folder --out {args.out}, which is replaced "
            "as a whole; choose a path outside it"
        )
    return kwargs


def run(args: argparse.Namespace) -> int:
    """Run the report per ``args``; the exit status."""
    from ..library.progress import mode_for
    from ..report.model import QUICK_NOT_RUN
    from ..report.render import quick_skipped
    from ..report.runner import run_report
    from ._library import library_options

    progress = mode_for(sys.stderr, not args.no_progress)  # a bar on a terminal, else lines
    if args.list_checks:  # the sections' declared tables: no section is built
        from ..report.runner import declared_checks

        for check_id, title in declared_checks(_sections(args, None), args.select, quick=args.quick):
            print(f"{check_id}\t{title}")
        return 0
    junit = _check_junit(args)  # before any work
    library = library_options(args, progress)  # before any work: --scheduler connects here
    try:
        under, subject = _under_test(args)
        result = run_report(
            args.paths,
            args.out,
            quick=args.quick,
            progress=progress,
            sections=_sections(args, under),
            select=args.select,
            under_test=under,
            subject=subject,
            library=library,
            explorer=_explorer(args),
        )
    finally:
        library.close()
    doc = result.document
    if args.junit:
        from ..report.junit import write_junit

        write_junit(doc, args.junit, force=args.force, **junit)
    ut = doc.get("implementation")
    if ut:
        print(ut["headline"])
        for v in ut["verdicts"]:
            err = "" if v["max_abs_error"] is None else f"  largest error {v['max_abs_error']:.3g}"
            print(f"  {v['label']:<10} {v['status']:<22} {v['sentence'] or v['detail']}{err}")
            if v["status"] == "does not conform" and v["where"]:
                print(f"           worst row (error / tolerance): {v['where']}")
    else:
        print(
            "No implementation under test: this report shows the reference's own evidence. "
            "Use --glsl/--cpp/--vectors/--implementation to grade yours."
        )
    print("The library's own evidence:")
    for s in doc["sections"]:
        ran = [c for c in s["checks"] if c["status"] != "not run"]
        n_pass = sum(c["passed"] for c in ran)
        reason = s["not_run"] or ""
        counts = (
            (reason if reason.startswith("not run") else f"not run: {reason}")
            if s["status"] == "not run"
            else f"{n_pass}/{len(ran)} checks"
        )
        skipped = sum(c["not_run"] == QUICK_NOT_RUN for c in s["checks"])
        if skipped and s["status"] != "not run":
            counts += f" ({skipped} not run in --quick)"
        print(f"  {s['key']:<16} {s['status']:<14} {counts}  {s['elapsed_s']:.1f} s")
    skipped = quick_skipped(doc)
    if skipped:
        print(
            "Quick run: not run here, and run by the full report (`openpbr-diffuse report`): "
            + ", ".join(f"{key} ({n} checks)" for key, _, n in skipped)
        )
    failed = [c for c in doc["checks"] if c["status"] == "fail"]
    for c in failed[:20]:
        print(f"  FAIL {c['id']}: {c['name']} (measured {c['measured']}, {c['comparison']} {c['threshold']})")
    ev = doc["evidence"]
    index = result.out_dir / "index.html" if result.out_dir is not None else "(not written)"
    if ev["n_checks"] == 0:
        print(f"NOT RUN: no check of the library's evidence ran; report in {index} ({doc['elapsed_s']:.1f} s)")
    else:
        print(
            f"{'PASS' if result.passed else 'FAIL'}: {ev['n_checks'] - ev['n_failed']}/{ev['n_checks']} checks "
            f"of the library's evidence; report in {index} ({doc['elapsed_s']:.1f} s)"
        )
    if ut:  # the tail of a CI log reads as the implementation's result
        print(ut["verdict_line"])
    return result.exit_status


__all__ = ["FAST_EVIDENCE", "add_parser", "run", "subject_from_args"]
