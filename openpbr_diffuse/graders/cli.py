"""``openpbr-diffuse check`` options that run an implementation's own code (hooked by cli/check.py).

    openpbr-diffuse check --implementation NAME [--source PATH] [--json]
    openpbr-diffuse check --glsl FILE --function NAME [--albedo-function NAME] [--include DIR] [--define N=V]
    openpbr-diffuse check --cpp FILE --function NAME [--albedo-function NAME] [--include DIR] [--define N=V]
    openpbr-diffuse check --glsl FILE --sample-function S --pdf-function P [--sampler-model eon] [--function F]

--glsl and --cpp compile and run the given code with the user's rights, each compile and run in a
child process under a wall-time limit (--timeout, default 60 s) and a 4 GiB memory limit; its whole
process group is killed on timeout or when the command is interrupted.

Exit status: 0 every graded quantity conforms, 1 one does not, 2 a piece is missing (GL driver,
compiler, bpy, source files) or the code does not compile.
"""

from __future__ import annotations

import argparse
import json
import math
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


def add_arguments(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """Add the grader options to a parser (``check``'s) or to an argument group of one.

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
        choices=sorted(IMPLEMENTATIONS),
        metavar="NAME",
        help="one of: " + ", ".join(IMPLEMENTATIONS),
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
    g.add_argument("--quick", action="store_true", help="fewer sampler samples (40k instead of 200k per case)")


def _print_text(result: ImplementationGrade) -> None:
    print(f"{result.name}: {'CONFORMS' if result.passed else 'DOES NOT CONFORM'} (reference model {result.model})")
    for k, v in result.version.items():
        if v not in (None, "", [], {}):
            print(f"  {k}: {v if not isinstance(v, list) else ', '.join(map(str, v))}")
    for q in result.quantities:
        verdict = "pass" if q.passed else "FAIL"
        print(
            f"  {q.quantity:30s} {verdict}  max {q.max_abs_error:.3g}  rms {q.rms_error:.3g}  "
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

    modes = [m for m in ("implementation", "glsl", "cpp") if getattr(args, m, None)]
    if not modes:
        for opt in ("source", "function", "albedo_function", "sample_function", "pdf_function", "sampler_model"):
            if getattr(args, opt, None):
                raise ValueError(f"check: --{opt.replace('_', '-')} needs --implementation, --glsl or --cpp")
        return None
    if len(modes) > 1 or getattr(args, "file", None):
        raise ValueError("check: give one of FILE, --implementation, --glsl, --cpp")
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
    from .grading import grade_subject

    subject = subject_from_args(args)
    if subject is None:
        return None
    _exit_on_sigterm()  # so a SIGTERM unwinds through run_limited, which kills the child's group
    result = grade_subject(
        subject,
        quick=args.quick,  # GraderUnavailable (an OSError): exit 2
        sampler_model=getattr(args, "sampler_model", None),
    )
    if args.json:
        print(json.dumps(result.to_dict()))
    else:
        _print_text(result)
    return 0 if result.passed else 1
