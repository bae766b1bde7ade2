"""``openpbr-diffuse check`` options that run an implementation's own code (hooked by cli/check.py).

    openpbr-diffuse check --implementation NAME [--source PATH] [--json]
    openpbr-diffuse check --glsl FILE --function NAME [--albedo-function NAME] [--include DIR] [--define N=V]
    openpbr-diffuse check --cpp FILE --function NAME [--albedo-function NAME] [--include DIR] [--define N=V]
    openpbr-diffuse check --wgsl FILE --function NAME [--albedo-function NAME]
    openpbr-diffuse check --glsl FILE --sample-function S --pdf-function P [--sampler-model eon] [--function F]

--glsl, --cpp and --wgsl compile and run the given code with the user's rights, each compile and run in a
child process under a wall-time limit (--timeout, default 60 s) and a 4 GiB memory limit; its whole
process group is killed on timeout or when the command is interrupted.

Exit status: 0 conforms (also "conforms with warnings"), 1 does not conform, 2 a piece is missing
(GL driver, compiler, bpy, source files), a function is missing or the code does not compile.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .grading import ImplementationGrade
    from .subject import Subject


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive number of seconds")
    return value


def add_arguments(parser: argparse.ArgumentParser | argparse._ArgumentGroup, renderers: Sequence[str] = ()) -> None:
    """Add the grader options to a parser (``check``'s) or to an argument group of one.

    ``renderers``: more ``--implementation`` names, graded from their image of the chart (the
    command line passes :data:`openpbr_diffuse.renderers.RENDERERS`; the graders do not import
    the renderers, which use them).

    >>> import argparse
    >>> p = argparse.ArgumentParser()
    >>> add_arguments(p)
    >>> p.parse_args(["--cpp", "f.cpp", "--function", "f", "--timeout", "5"]).timeout
    5.0
    """
    from . import IMPLEMENTATIONS, limits

    if isinstance(parser, argparse._ArgumentGroup):
        g = parser
    else:
        g = parser.add_argument_group(
            "grade an implementation by running its own code",
            "--glsl and --cpp COMPILE AND RUN THE GIVEN CODE WITH YOUR USER'S RIGHTS (in a child process "
            f"with a time limit, --timeout, default {limits.TIMEOUT:g} s, and a "
            f"{limits.MEMORY / 2**30:g} GiB memory limit): grade only code you would run yourself",
        )
    g.add_argument(
        "--implementation",
        choices=sorted(IMPLEMENTATIONS) + sorted(renderers),
        metavar="NAME",
        help="one of: "
        + ", ".join(IMPLEMENTATIONS)
        + ("; or a renderer, whose image of the chart is graded: " + ", ".join(renderers) if renderers else ""),
    )
    g.add_argument("--source", metavar="PATH", help="the implementation's checkout (its code is not in a package)")
    g.add_argument(
        "--glsl",
        metavar="FILE",
        help="a GLSL file holding FUNCTION (see --function); compiled and run on llvmpipe with your rights",
    )
    g.add_argument(
        "--cpp",
        metavar="FILE",
        help="a C++ file holding FUNCTION (see --function); compiled with g++ and run with your rights",
    )
    g.add_argument(
        "--wgsl",
        metavar="FILE",
        help="a WGSL file holding FUNCTION, fn NAME(wi: vec3<f32>, wo: vec3<f32>, roughness: f32, rho: vec3<f32>) "
        "-> vec3<f32> (and the albedo fn NAME(mu: f32, roughness: f32, rho: vec3<f32>) -> vec3<f32>); run through "
        "wgpu (lavapipe) with your rights",
    )
    g.add_argument(
        "--function",
        metavar="NAME",
        help="BRDF function: vec3 NAME(vec3 wi, vec3 wo, float roughness, vec3 rho), local frame, no cosine",
    )
    g.add_argument(
        "--albedo-function", metavar="NAME", help="albedo function: vec3 NAME(float mu, float roughness, vec3 rho)"
    )
    g.add_argument(
        "--sample-function",
        metavar="NAME",
        help="sampler: vec3 NAME(vec3 wo, vec2 u, float roughness) -> wi, u in [0, 1)^2, local frame "
        "(with --pdf-function)",
    )
    g.add_argument(
        "--pdf-function", metavar="NAME", help="its solid-angle pdf: float NAME(vec3 wo, vec3 wi, float roughness)"
    )
    from ..sampling.registry import STRATEGIES

    g.add_argument(
        "--sampler-model",
        choices=STRATEGIES,
        metavar="STRATEGY",
        help="the reference strategy the sampler claims to implement (e.g. eon): its pdf must then "
        "match that one's; default: compared and reported, not graded",
    )
    g.add_argument("--include", metavar="DIR", action="append", default=[], help="include path (repeatable)")
    g.add_argument(
        "--define", metavar="NAME=VALUE", action="append", default=[], help="preprocessor define (repeatable)"
    )
    g.add_argument(
        "--timeout",
        metavar="SECONDS",
        type=_seconds,
        default=None,
        help=f"wall-time limit of each compile and run of --glsl/--cpp code (default {limits.TIMEOUT:g})",
    )
    g.add_argument(
        "--quick",
        action="store_true",
        help="accepted for scripts: the sampler's sample count is the same in check and report "
        "(graders.grading.SAMPLER_SAMPLES)",
    )


def add_tier_arguments(parser: argparse.ArgumentParser) -> None:
    """``--precision`` and ``--expect-fail`` of ``check`` (all its modes).

    >>> import argparse
    >>> p = argparse.ArgumentParser()
    >>> add_tier_arguments(p)
    >>> p.parse_args(["--precision", "half", "--expect-fail", "x.txt"]).precision
    'half'
    """
    from ..conformance.grade import PRECISIONS

    g = parser.add_argument_group("tiers: conforms / conforms with warnings / does not conform")
    g.add_argument(
        "--precision",
        choices=PRECISIONS,
        default=None,
        help="the precision your implementation works in: with half, values off by at most 1 ulp of float16 "
        "conform with a warning",
    )
    g.add_argument(
        "--expect-fail",
        metavar="FILE",
        help="a text file of check ids (one per line, # comments) expected to fail: they do not fail the run; "
        "a listed check that passes is reported",
    )


def checks_of(result: ImplementationGrade) -> list[dict]:
    """The checks (id, status, detail) of an implementation's grade: ``values.<quantity>`` for
    the values, the sub-checks (``property.*``, ``sampler_*``) of the others."""
    from ..conformance.tiers import check_from_grade
    from ..result import sub_check

    checks = []
    for q in result.quantities:
        if q.checks:
            for c in q.checks:
                status = {"info": "pass"}.get(c["status"], c["status"])
                checks.append({**c, "status": status, "verdict": status})
        elif q.values is not None:
            checks.append(check_from_grade(f"values.{q.quantity.replace(' ', '_')}", q.values))
        else:
            name = q.quantity.replace(" ", "_")
            checks.append(sub_check(name, "pass" if q.passed else "fail", q.measured, q.threshold, q.detail).to_dict())
    return checks


def prepare(args: argparse.Namespace, inputs: list) -> list[str]:
    """Before any grading: the --expect-fail ids (ValueError when unreadable) and the --junit
    path checked (never overwritten without --force, never an input)."""
    from ..conformance.tiers import read_expect_fail

    expected = read_expect_fail(args.expect_fail) if getattr(args, "expect_fail", None) else []
    if getattr(args, "junit", None):
        from .._outfile import check_output_file

        check_output_file(
            args.junit,
            option="--junit",
            force=getattr(args, "force", False),
            inputs=[x for x in (*inputs, args.expect_fail) if x],
        )
    return expected


def finish(
    args: argparse.Namespace,
    name: str,
    checks: list[dict],
    expected: list[str],
    doc: dict | None,
    show: Callable[[], None],
) -> int:
    """Apply --expect-fail, decide the tier, print (text or ``doc`` as JSON), write --junit;
    returns the exit status (0 conforms, also with warnings; 1 does not conform)."""
    from ..conformance.tiers import EXIT, apply_expected, junit_xml, print_checks, tier_of

    checks, notes = apply_expected(checks, expected, str(getattr(args, "expect_fail", None) or "FILE"))
    tier = tier_of(checks)
    if args.json:
        assert doc is not None
        doc.update({"tier": tier, "checks": checks, "expect_fail_notes": notes})
        print(json.dumps(doc))
    else:
        show()
        print_checks(checks)
        for n in notes:
            print(f"  note: {n}")
        print(f"  result: {tier}")
    if getattr(args, "junit", None):
        from .._outfile import write_output_file

        write_output_file(
            args.junit, junit_xml(name, checks, tier), option="--junit", force=getattr(args, "force", False)
        )
    return EXIT[tier]


def _num(x: float) -> str:
    return "-" if isinstance(x, float) and math.isnan(x) else f"{x:.3g}"


def _print_text(result: ImplementationGrade) -> None:
    from ..conformance.text import print_grade
    from ..conformance.tiers import tier_of

    # the tier of its checks (before --expect-fail, which the last line applies)
    print(f"{result.name}: {tier_of(checks_of(result)).upper()} (reference model {result.model})")
    for k, v in result.version.items():
        if v not in (None, "", [], {}):
            print(f"  {k}: {v if not isinstance(v, list) else ', '.join(map(str, v))}")
    for q in result.quantities:
        if q.values is not None:  # the values: the same text as check FILE (regions, worst rows)
            print_grade(q.values, f"  {q.quantity}")
            if q.excluded:
                print(f"  ({q.excluded} rows outside its input domain)")
            continue
        verdict = "pass" if q.passed else "FAIL"
        errors = (
            f"  max {_num(q.max_abs_error)}  rms {_num(q.rms_error)}"
            if not (math.isnan(q.max_abs_error) and math.isnan(q.rms_error))
            else ""
        )
        print(
            f"  {q.quantity:30s} {verdict}{errors}  "
            f"[{q.tolerance}]" + (f"  ({q.excluded} rows outside its input domain)" if q.excluded else "")
        )
        if q.sentence is not None:  # the sampler's quantities: a sentence and sub-checks with ids
            print(f"      {'diagnosis: ' + (q.diagnosis or 'none') + ' -- ' if not q.passed else ''}{q.sentence}")
            for c in q.checks:
                print(f"      [{c['status']}] {c['id']}: {c['detail']}")
            for label, text in (q.regions or {}).items():
                print(f"        {label}: {text}")
        elif q.diagnosis or not q.passed:
            print(f"      diagnosis: {q.diagnosis or 'none'} -- {q.detail}")
        else:
            print(f"      {q.detail}")
    for note in result.notes:
        print(f"  note: {note}")


#: a source file larger than this is not searched for the functions (the compiler names them)
_MAX_SOURCE_SCAN = 16 << 20


def _check_functions(path: str, names: Iterable[str | None]) -> None:
    """ValueError "no function NAME(...) in FILE" for a function name the source never writes
    followed by "(".  A file with ``#include`` (the function may be in the included file) or
    token pasting (``##``), an unreadable or a huge one is left to the compiler, whose message
    :func:`_missing_function` translates.

    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "mine.glsl"
    >>> _ = p.write_text("vec3 f (vec3 wi, vec3 wo, float r, vec3 rho) { return rho; }")
    >>> _check_functions(str(p), ("f", None))
    >>> _check_functions(str(p), ("eon_f",))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: no function eon_f(...) in .../mine.glsl
    """
    import re
    from pathlib import Path

    try:
        if Path(path).stat().st_size > _MAX_SOURCE_SCAN:
            return
        text = Path(path).read_bytes().decode("utf-8", errors="replace")
    except OSError:
        return
    for name in names:
        if name and not re.search(r"(?<![A-Za-z0-9_])" + re.escape(name) + r"\s*\(", text):
            if "##" in text or re.search(r"^\s*#\s*include", text, re.M):  # let the compiler say
                continue
            raise ValueError(f"no function {name}(...) in {path}")


#: a compiler's words for a name that is not declared: g++ and Mesa's GLSL compiler
_UNDECLARED = (
    r"[‘'`]{name}[’']? was not declared",
    r"no function with name '{name}'",
    r"[‘']{name}[’'] is not a member",
    r"no definition in scope for identifier: [`']?{name}\b",
)


def _missing_function(message: str, path: str | None, names: Iterable[str | None]) -> str | None:
    """ "no function NAME(...) in FILE" when a compiler ``message`` says NAME is not declared.

    >>> _missing_function("x does not compile: 0:10(18): error: no function with name 'eon_f'", "a.glsl", ["eon_f"])
    'no function eon_f(...) in a.glsl'
    >>> _missing_function("error: ‘g’ was not declared in this scope", "a.cpp", ["f"]) is None
    True
    """
    import re

    for name in names:
        if name and any(re.search(p.format(name=re.escape(name)), message) for p in _UNDECLARED):
            return f"no function {name}(...) in {path}"
    return None


def subject_from_args(args: argparse.Namespace) -> Subject | None:
    """The Subject the options name (``--implementation``/``--glsl``/``--cpp``), or None without one.

    Applies ``--timeout`` to the limits of user code; raises ValueError for inconsistent options.

    >>> import argparse
    >>> subject_from_args(argparse.Namespace(implementation=None, glsl=None, cpp=None)) is None
    True
    """
    from . import limits, load
    from .generic import cpp_subject, glsl_subject

    if getattr(args, "timeout", None) is not None:
        limits.set_limits(timeout=args.timeout)

    modes = [m for m in ("implementation", "glsl", "cpp", "wgsl") if getattr(args, m, None)]
    if not modes:
        for opt in ("source", "function", "albedo_function", "sample_function", "pdf_function", "sampler_model"):
            if getattr(args, opt, None):
                raise ValueError(f"check: --{opt.replace('_', '-')} needs --implementation, --glsl or --cpp")
        return None
    if len(modes) > 1 or getattr(args, "file", None):
        raise ValueError("check: give one of FILE, --implementation, --glsl, --cpp, --wgsl")
    if getattr(args, "wgsl", None):
        from .wgsl import wgsl_subject

        for opt in ("source", "sample_function", "pdf_function", "sampler_model", "include", "define"):
            if getattr(args, opt, None):
                raise ValueError(f"check: --{opt.replace('_', '-')} is not available with --wgsl")
        _check_functions(args.wgsl, (args.function, args.albedo_function))
        return wgsl_subject(args.wgsl, args.function, args.albedo_function, model=getattr(args, "model", None) or "eon")
    if args.implementation:
        if (
            args.function
            or args.albedo_function
            or getattr(args, "sample_function", None)
            or getattr(args, "pdf_function", None)
        ):
            raise ValueError("check: --function / --sample-function are for --glsl / --cpp, not --implementation")
        subject = load(args.implementation, args.source)
    else:
        if args.source:
            raise ValueError("check: --source is for --implementation")
        make = glsl_subject if args.glsl else cpp_subject
        _check_functions(
            args.glsl or args.cpp,
            (
                args.function,
                args.albedo_function,
                getattr(args, "sample_function", None),
                getattr(args, "pdf_function", None),
            ),
        )
        subject = make(
            args.glsl or args.cpp,
            args.function,
            args.albedo_function,
            includes=args.include,
            defines=args.define,
            model=getattr(args, "model", None) or "eon",
            sample_function=getattr(args, "sample_function", None),
            pdf_function=getattr(args, "pdf_function", None),
        )
    return subject


def _exit_on_sigterm() -> None:
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return
    for sig in (signal.SIGTERM, signal.SIGHUP):
        if signal.getsignal(sig) in (signal.SIG_DFL, None):
            signal.signal(sig, lambda signum, frame: (_ for _ in ()).throw(SystemExit(128 + signum)))


def run(args: argparse.Namespace) -> int | None:
    """Grade per the options, or return None when none of them is given (``check FILE`` mode)."""
    from .errors import GraderUnavailable
    from .grading import grade_subject

    if not any(getattr(args, m, None) for m in ("implementation", "glsl", "cpp", "wgsl")):
        subject_from_args(args)  # ValueError for an option that needs a mode
        return None
    code = args.glsl or args.cpp or getattr(args, "wgsl", None)
    expected = prepare(args, [code] if code else [])  # before any compile
    _exit_on_sigterm()  # so a SIGTERM unwinds through run_limited, which kills the child's group
    try:
        subject = subject_from_args(args)
        assert subject is not None
        result = grade_subject(
            subject,
            quick=args.quick,  # GraderUnavailable (an OSError): exit 2
            sampler_model=getattr(args, "sampler_model", None),
            precision=getattr(args, "precision", None),
        )
    except GraderUnavailable as exc:  # a compiler's "not declared": the function is missing
        names = [getattr(args, k, None) for k in ("function", "albedo_function", "sample_function", "pdf_function")]
        missing = _missing_function(str(exc), code, names) if code else None
        if missing is None:
            raise
        raise GraderUnavailable(missing) from None
    return finish(
        args,
        result.name,
        checks_of(result),
        expected,
        result.to_dict() if args.json else None,
        lambda: _print_text(result),
    )
